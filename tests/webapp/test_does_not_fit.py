"""A recording of another exercise is a result, not a failure (issue 25): the run succeeds with
no repetition and no score, says "does not look like" in plain words naming the clinic's
exercise it looks like, on the recording page, in the API result and in the exports. An exercise
that cannot analyse yet fails its runs with a plain reason, not the generic one."""

from __future__ import annotations

import pytest
from django.urls import reverse
from rest_framework.test import APIClient

from tests.personas import make_exercise, make_recording
from webapp.patients.models import PerformanceLevel
from webapp.recordings.models import AnalysisRun
from workers.analysis_task import GENERIC_FAILURE, analyse_run


@pytest.fixture
def mismatched(world):
    squat = make_exercise(world.clinic, "Deep squat", "reps/m01_s01_e01.bvh.gz")
    arms = make_exercise(world.clinic, "Shoulder abduction", "reps/m07_s01_e01.bvh.gz")
    recording = make_recording(world.patient, squat, source="reps/m07_s01_e02.bvh.gz")
    assert analyse_run(str(recording.runs.get().pk)) == "succeeded"
    return recording, squat, arms


def test_the_run_succeeds_without_repetitions_or_score(world, mismatched):
    recording, _, arms = mismatched
    run = recording.runs.get()
    assert run.score is None and run.summary["score"] is None
    assert run.summary["repetitions"] == [] and run.result.repetition_count == 0
    match = run.summary["match"]
    assert match["fits"] is False and match["looks_like"] == str(arms.pk)
    assert match["message"].startswith("This recording does not look like the exercise")
    assert "\u201cShoulder abduction\u201d" in match["message"]
    assert not PerformanceLevel.objects.filter(patient=world.patient).exists()  # level untouched


def test_the_recording_page_says_so_in_plain_words(client, world, mismatched):
    recording = mismatched[0]
    client.force_login(world.therapist)
    page = client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).content.decode()
    assert 'id="does-not-fit"' in page and "does not look like" in page
    assert "no score" in page and "/ 100" not in page and "0 of 0" not in page
    assert "did not form a repeating cycle" not in page  # no repetition to explain


def test_the_api_result_and_exports_carry_it(world, mismatched):
    recording = mismatched[0]
    api = APIClient()
    api.force_authenticate(world.therapist)
    body = api.get(f"/api/v1/recordings/{recording.pk}/").json()
    assert body["status"] == "succeeded"
    assert body["result"]["score"] is None and body["result"]["repetitions"] == []
    assert body["result"]["match"]["fits"] is False
    history = api.get(f"/api/v1/patients/{world.patient.pk}/history.csv")
    assert history.status_code == 200
    fhir = api.get(f"/api/v1/patients/{world.patient.pk}/fhir/").json()
    scores = [e["resource"] for e in fhir["entry"] if "session-score" in str(e["resource"])]
    assert scores and "dataAbsentReason" in scores[0] and "valueQuantity" not in scores[0]


def test_the_right_exercise_still_fits(world):
    arms = make_exercise(world.clinic, "Shoulder abduction", "reps/m07_s01_e01.bvh.gz")
    make_exercise(world.clinic, "Deep squat", "reps/m01_s01_e01.bvh.gz")
    recording = make_recording(world.patient, arms, source="reps/m07_s01_e02.bvh.gz")
    assert analyse_run(str(recording.runs.get().pk)) == "succeeded"
    run = recording.runs.get()
    assert run.summary["match"] == {"fits": True} and run.score is not None
    assert len(run.summary["repetitions"]) == 1


def test_an_exercise_without_key_poses_fails_with_a_plain_reason(world):
    exercise = make_exercise(world.clinic)
    exercise.tutor_landmark_frames, exercise.tutor_landmark_types = [], []
    exercise.save()
    recording = make_recording(world.patient, exercise)
    assert analyse_run(str(recording.runs.get().pk)) == "failed"
    run = AnalysisRun.objects.get(recording=recording)
    assert run.user_error != GENERIC_FAILURE
    assert "cannot analyse recordings yet" in run.user_error
    assert "trying again before that cannot help" in run.user_error
