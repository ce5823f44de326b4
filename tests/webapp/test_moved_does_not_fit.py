"""One wrong-exercise rule before and after a move (issue 35, item 6): a recording moved to an
exercise it does not fit is analysed again against that exercise and told "does not look like"
again, naming the same exercise it looks like; moved to that exercise, as advised, it fits."""

from __future__ import annotations

import pytest
from django.urls import reverse
from rest_framework.test import APIClient

from tests.personas import make_exercise, make_recording
from workers.analysis_task import analyse_run


@pytest.fixture
def clinic_of_three(world, monkeypatch):
    """Deep squat, hurdle step and shoulder abduction; a shoulder abduction uploaded as the
    squat and analysed."""
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda run_id: None)
    squat = make_exercise(world.clinic, "Deep squat", "reps/m01_s01_e01.bvh.gz")
    hurdle = make_exercise(world.clinic, "Hurdle step", "reps/m02_s01_e01.bvh.gz")
    arms = make_exercise(world.clinic, "Shoulder abduction", "reps/m07_s01_e01.bvh.gz")
    recording = make_recording(world.patient, squat, source="reps/m07_s01_e02.bvh.gz")
    assert analyse_run(str(recording.runs.get().pk)) == "succeeded"
    return recording, hurdle, arms


def moved(world, recording, exercise) -> dict:
    """Move the recording through the API, run the queued analysis, return its result."""
    api = APIClient()
    api.force_authenticate(world.therapist)
    answer = api.patch(
        f"/api/v1/recordings/{recording.pk}/", {"exercise": str(exercise.pk)}, format="json"
    )
    assert answer.status_code == 200, answer.content
    run_id = answer.json()["run"]["id"]
    assert analyse_run(run_id) == "succeeded"
    body = api.get(f"/api/v1/recordings/{recording.pk}/").json()
    assert body["run"]["id"] == run_id and body["exercise"] == str(exercise.pk)
    return body["result"]


def test_moved_to_another_wrong_exercise_it_is_told_so_again(world, clinic_of_three, client):
    recording, hurdle, arms = clinic_of_three
    first = recording.runs.get().summary["match"]
    assert first["fits"] is False and first["looks_like"] == str(arms.pk)
    result = moved(world, recording, hurdle)
    match = result["match"]
    assert match["fits"] is False and match["looks_like"] == str(arms.pk)
    assert match["message"].startswith("This recording does not look like the exercise")
    assert "\u201cHurdle step\u201d" in match["message"]
    assert result["score"] is None and result["repetitions"] == []
    client.force_login(world.therapist)
    page = client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).content.decode()
    assert 'id="does-not-fit"' in page and "Hurdle step" in page and "/ 100" not in page


def test_moved_to_the_exercise_it_looks_like_it_fits(world, clinic_of_three):
    recording, _, arms = clinic_of_three
    result = moved(world, recording, arms)
    assert result["match"] == {"fits": True}
    assert result["score"] is not None and len(result["repetitions"]) == 1
