"""Uploading without an exercise: a worker recognises it (paper 002 retrieval; eager here, its
message handed over after the commit) and the uploader confirms before analysing; page and API."""

from __future__ import annotations

import datetime

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.test import TestCase
from django.urls import reverse
from rest_framework.test import APIClient

from tests.personas import fixture_bytes, make_exercise
from webapp.recordings.models import AnalysisRun, Recording

SQUAT = "reps/m01_s01_e02.bvh.gz"


@pytest.fixture
def exercises(world):
    squat = make_exercise(world.clinic, source="reps/m01_s01_e01.bvh.gz")
    abduction = make_exercise(
        world.clinic, name="Shoulder abduction", source="reps/m07_s01_e01.bvh.gz"
    )
    return squat, abduction


def upload_page(client, world, content: bytes):
    data = {
        "patient": str(world.patient.pk),
        "exercise": "",
        "file": SimpleUploadedFile("t.bvh.gz", content),
    }
    with TestCase.captureOnCommitCallbacks(execute=True):  # the eager recognition runs
        return client.post(reverse("recordings:upload"), data)


def confirm_url(recording) -> str:
    return reverse("recordings:confirm", kwargs={"pk": recording.pk})


def test_page_upload_without_exercise_suggests_and_confirms(
    client, world, exercises, django_capture_on_commit_callbacks
):
    squat, _ = exercises
    client.force_login(world.patient_user)
    response = upload_page(client, world, fixture_bytes(SQUAT))
    recording = Recording.objects.get()
    assert response.status_code == 302
    assert response["Location"] == reverse("recordings:detail", kwargs={"pk": recording.pk})
    assert recording.exercise is None and recording.suggested_exercise == squat
    assert not AnalysisRun.objects.exists(), "nothing is analysed before the confirmation"
    page = client.get(confirm_url(recording))
    assert "Deep squat" in page.content.decode()
    with django_capture_on_commit_callbacks(execute=True):
        answer = client.post(confirm_url(recording), {"exercise": str(squat.pk)})
    assert answer.status_code == 302
    recording.refresh_from_db()
    assert recording.exercise == squat
    assert AnalysisRun.objects.get().status == "succeeded"


def test_other_exercise_is_recognised(client, world, exercises):
    _, abduction = exercises
    client.force_login(world.therapist)
    upload_page(client, world, fixture_bytes("reps/m07_s01_e02.bvh.gz"))
    assert Recording.objects.get().suggested_exercise == abduction


def test_confirming_a_mismatched_skeleton_is_a_form_error(client, world, exercises, settings):
    import gzip

    squat, _ = exercises
    text = gzip.decompress(fixture_bytes(SQUAT)).decode().replace("LeftFoot", "LeftPaw")
    client.force_login(world.therapist)
    upload_page(client, world, gzip.compress(text.encode()))
    answer = client.post(confirm_url(Recording.objects.get()), {"exercise": str(squat.pk)})
    assert answer.status_code == 400
    assert "skeleton does not match" in answer.content.decode()
    assert Recording.objects.get().exercise is None and not AnalysisRun.objects.exists()


def test_api_upload_without_exercise_then_confirm(world, exercises, monkeypatch):
    squat, abduction = exercises
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda run_id: None)
    api = APIClient()
    api.force_authenticate(world.therapist)
    with TestCase.captureOnCommitCallbacks(execute=True):  # the eager recognition runs
        created = api.post(
            "/api/v1/recordings/",
            {
                "patient": str(world.patient.pk),
                "file": SimpleUploadedFile("t.bvh.gz", fixture_bytes(SQUAT)),
            },
            format="multipart",
        )
    assert created.status_code == 201, created.content
    body = created.json()
    assert body["status"] is None and body["recognition"] == "queued"
    recognised = api.get(f"/api/v1/recordings/{body['id']}/").json()
    assert recognised["suggested_exercise"] == str(squat.pk) and recognised["recognition"] == "done"
    url = f"/api/v1/recordings/{body['id']}/confirm/"
    assert api.post(url, {"exercise": "nonsense"}, format="json").status_code == 400
    other_clinic = make_exercise(world.other_clinic, name="Elsewhere")
    assert api.post(url, {"exercise": str(other_clinic.pk)}, format="json").status_code == 400
    confirmed = api.post(url, {"exercise": str(abduction.pk)}, format="json")
    assert confirmed.status_code == 200
    assert (
        confirmed.json()["exercise"] == str(abduction.pk) and confirmed.json()["status"] == "queued"
    )
    again = api.post(url, {"exercise": str(squat.pk)}, format="json")
    assert again.status_code == 400 and "already set" in again.content.decode()
    assert AnalysisRun.objects.count() == 1


def test_prescribed_exercises_are_preferred(client, world, exercises):
    from webapp.patients.models import Prescription

    _, abduction = exercises
    Prescription.objects.create(
        patient=world.patient, exercise=abduction, start_date=datetime.date.today()
    )
    client.force_login(world.therapist)
    upload_page(client, world, fixture_bytes(SQUAT))
    assert Recording.objects.get().suggested_exercise == abduction
