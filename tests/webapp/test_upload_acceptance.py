"""One acceptance of an upload (`webapp.recordings.uploads.accept_upload`, issue 22 item 4): the
upload page and ``POST /api/v1/recordings/`` store the same file the same way, and a patient's
answers (pain, note, effort) are stored with the recording, also when the same file completes an
upload that still waits for its exercise."""

from __future__ import annotations

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.urls import reverse
from django.utils import timezone
from rest_framework.test import APIClient

from tests.personas import fixture_bytes, make_exercise
from webapp.patients.models import Prescription
from webapp.recordings.models import AnalysisRun, Recording
from webapp.recordings.uploads import accept_upload, parse_upload

GOOD = "reps/m01_s01_e02.bvh.gz"
SAME = ("n_frames", "n_joints", "fps", "checksum", "pain_score", "note", "exercise_id")


@pytest.fixture(autouse=True)
def _no_queue(monkeypatch):
    """What is stored is the question here; the analysis is tested elsewhere."""
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda run_id: None)
    monkeypatch.setattr("workers.tasks.recognise_exercise.delay", lambda recording_id: None)


@pytest.fixture
def exercise(world):
    return make_exercise(world.clinic)


def form_data(patient, exercise) -> dict:
    return {
        "patient": str(patient.pk), "exercise": str(exercise.pk) if exercise else "",
        "pain_score": "2", "note": "left knee sore",
        "file": SimpleUploadedFile("t.bvh.gz", fixture_bytes(GOOD)),
    }  # fmt: skip


def test_the_page_and_the_api_store_an_upload_alike(client, world, exercise):
    client.force_login(world.therapist)
    page = client.post(reverse("recordings:upload"), form_data(world.patient, exercise))
    assert page.status_code == 302
    api = APIClient()
    api.force_authenticate(world.therapist)
    answer = api.post("/api/v1/recordings/", form_data(world.other_patient, exercise))
    assert answer.status_code == 201, answer.content
    by_page = Recording.objects.get(patient=world.patient)
    by_api = Recording.objects.get(patient=world.other_patient)
    assert [getattr(by_page, f) for f in SAME] == [getattr(by_api, f) for f in SAME]
    assert by_page.pain_score == 2 and by_page.note == "left knee sore"
    assert AnalysisRun.objects.filter(status="queued").count() == 2


def test_a_patients_effort_is_stored_with_a_waiting_upload_they_complete(client, world, exercise):
    Prescription.objects.create(
        patient=world.patient, exercise=exercise, start_date=timezone.localdate()
    )
    client.force_login(world.patient_user)
    waiting = form_data(world.patient, None)
    assert client.post(reverse("recordings:upload"), waiting).status_code == 302
    assert Recording.objects.get().runs.count() == 0  # waits for its exercise
    again = {**form_data(world.patient, exercise), "effort": "7"}
    assert client.post(reverse("recordings:upload"), again).status_code == 302
    recording = Recording.objects.get()  # the same upload, completed
    assert recording.effort == 7 and recording.exercise_id == exercise.pk
    assert recording.runs.count() == 1


def test_accepting_needs_the_parsed_file_of_a_valid_form(world, exercise):
    parsed = parse_upload(SimpleUploadedFile("t.bvh.gz", fixture_bytes(GOOD)))
    data = {"patient": world.patient, "exercise": exercise, "effort": 4}
    recording, run = accept_upload(parsed, data, world.patient_user)
    assert recording.effort == 4 and recording.note == "" and run is not None
    with pytest.raises(ValueError, match="valid upload form"):
        accept_upload(None, data, world.patient_user)
