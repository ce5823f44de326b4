"""The patient's own pages (issue 24): how hard a session felt (Borg CR10, 0–10) on the upload
form and the result page, the result in lay words, and the progress page."""

from __future__ import annotations

import datetime

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.urls import reverse

from analysis.feedback.advice import Advice, Correction
from analysis.pipeline import AnalysisSummary
from analysis.pipeline.results import RepetitionResult
from tests.personas import fixture_bytes, make_exercise, make_recording
from webapp.dashboard.lay_words import lay_result, regions_of, relevant_praise
from webapp.patients.models import Goal, Prescription
from webapp.recordings.models import Recording, RunStatus

THERAPIST_WORDS = ("key pose", "level", "% of its range", "normal range", "landmark", "GBDTW")
TIPS = (
    "Raise your left arm about 15° higher (repetitions 1 and 3).",
    "Keep your trunk still (every repetition).",
    "Slow down a little (repetition 2).",
    "Bend your right elbow less (repetition 4).",
)


@pytest.fixture
def squat(world):
    exercise = make_exercise(world.clinic, source="reps/m01_s01_e01.bvh.gz")
    start = datetime.date.today() - datetime.timedelta(days=7)
    Prescription.objects.create(patient=world.patient, exercise=exercise, start_date=start)
    return exercise


def summary(scores: list[float], went_well: tuple[str, ...] = ()) -> AnalysisSummary:
    reps = tuple(
        RepetitionResult(10 * i, 10 * i + 9, 10 * i + 5, s, passed=s >= 70)  # as the analysis
        for i, s in enumerate(scores)
    )
    corrections = tuple(Correction(text, "left arm", "raise", 15.0, "°", (1,), 0) for text in TIPS)
    return AnalysisSummary(
        frames=100, fps=30.0, landmarks=(), repetitions=reps, score=60.0,
        advice=Advice(corrections, went_well),
    )  # fmt: skip


def finished(recording: Recording, result: AnalysisSummary) -> Recording:
    run = recording.runs.first()
    run.status, run.summary = RunStatus.SUCCEEDED, result.to_json()
    run.save()
    return recording


def test_patient_upload_saves_the_effort(world, client, squat, monkeypatch):
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda *args: None)
    client.force_login(world.patient_user)
    page = client.get(reverse("recordings:upload")).content.decode()
    assert 'name="effort"' in page and "How hard did it feel?" in page
    data = {
        "exercise": str(squat.pk),
        "file": SimpleUploadedFile("s.bvh.gz", fixture_bytes("reps/m01_s01_e02.bvh.gz")),
        "effort": "6",
    }
    response = client.post(reverse("recordings:upload"), data)
    assert response.status_code == 302
    assert Recording.objects.get(patient=world.patient).effort == 6


@pytest.mark.parametrize("effort", ["11", "-1", "four"])
def test_effort_outside_0_to_10_is_refused(world, client, squat, effort):
    client.force_login(world.patient_user)
    data = {
        "exercise": str(squat.pk),
        "file": SimpleUploadedFile("s.bvh.gz", fixture_bytes("reps/m01_s01_e02.bvh.gz")),
        "effort": effort,
    }
    assert client.post(reverse("recordings:upload"), data).status_code == 400
    assert not Recording.objects.filter(patient=world.patient).exists()


def test_patient_pages_do_not_send_the_patient_to_the_clinics_guide(world, client, squat):
    client.force_login(world.patient_user)
    home = client.get(reverse("dashboard:home")).content.decode()
    assert f'href="{reverse("help:guide")}"' not in home
    assert f'href="{reverse("dashboard:my-progress")}"' in home  # their own progress instead


def test_staff_upload_form_does_not_ask_the_effort(world, client):
    client.force_login(world.therapist)
    assert 'name="effort"' not in client.get(reverse("recordings:upload")).content.decode()


def test_effort_given_on_the_result_page_reaches_the_therapist(world, client, squat):
    recording = finished(make_recording(world.patient, squat), summary([80, 50]))
    client.force_login(world.patient_user)
    url = reverse("dashboard:my-effort", args=[recording.pk])
    assert client.post(url, {"effort": "12"}).status_code == 400
    recording.refresh_from_db()
    assert recording.effort is None
    assert client.post(url, {"effort": "4"}).status_code == 302
    recording.refresh_from_db()
    assert recording.effort == 4
    client.force_login(world.therapist)
    assert client.post(url, {"effort": "9"}).status_code == 403  # the patient's answer only
    page = client.get(reverse("recordings:detail", args=[recording.pk])).content.decode()
    assert "effort 4/10" in page


def test_patient_gets_the_lay_result_not_the_technical_page(world, client, squat):
    recording = finished(make_recording(world.patient, squat), summary([90, 75, 40, 71, 20]))
    client.force_login(world.patient_user)
    response = client.get(reverse("recordings:detail", args=[recording.pk]))
    html = response.content.decode()
    assert response.templates[0].name == "recordings/patient_result.html"
    assert '<p class="big-figure" id="reps-done">5</p>' in html
    assert '<p class="big-figure" id="reps-well">3</p>' in html  # scores at or above 70
    assert all(tip in html for tip in TIPS[:3]) and TIPS[3] not in html  # three tips at most
    assert not [word for word in THERAPIST_WORDS if word.lower() in html.lower()]
    client.force_login(world.therapist)
    staff = client.get(reverse("recordings:detail", args=[recording.pk]))
    assert staff.templates[0].name == "recordings/detail.html"


def test_praise_of_a_body_region_the_exercise_does_not_train_is_left_out():
    praise = ("Your left ankle stayed steady.", "Good rhythm.", "Your arms rose evenly.")
    assert relevant_praise(praise, {"arms"}) == ("Good rhythm.", "Your arms rose evenly.")
    assert relevant_praise(praise, set()) == praise  # unknown regions: nothing is dropped
    assert regions_of("left upper arm") == {"arms"} and regions_of("right thigh") == {"legs"}


def test_praise_follows_the_tips_body_parts_when_joints_are_unknown():
    result = summary([80], went_well=("Your knees stayed level.", "Your arm moved smoothly."))
    lay = lay_result(result, exercise=None)  # every tip corrects the "left arm"
    assert lay.went_well == ("Your arm moved smoothly.",)
    assert (lay.done, lay.done_well) == (1, 1)


def test_progress_page_charts_each_exercise(world, client, squat):
    finished(make_recording(world.patient, squat), summary([90, 80, 10]))
    Goal.objects.create(
        patient=world.patient, exercise=squat, measure="knee_flexion_left", target=95,
        by=datetime.date.today() + datetime.timedelta(days=30),
    )  # fmt: skip
    client.force_login(world.patient_user)
    html = client.get(reverse("dashboard:my-progress")).content.decode()
    assert "Deep squat" in html and "2 of 3 repetitions done well" in html
    assert "goal 95° by" in html
    client.force_login(world.therapist)
    assert client.get(reverse("dashboard:my-progress")).status_code == 403
