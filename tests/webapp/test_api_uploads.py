"""Uploads through the API: every refused file answers 400 naming the problem and stores nothing
(no recording, no run, no file); the page shows the same reasons as form errors."""

from __future__ import annotations

import gzip

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from rest_framework.test import APIClient

from tests.personas import fixture_bytes, make_exercise
from tests.webapp.test_uploads import GOOD, assert_nothing_stored
from webapp.recordings.models import Recording


@pytest.fixture
def api(world) -> APIClient:
    client = APIClient()
    client.force_authenticate(world.therapist)
    return client


@pytest.fixture
def exercise(world):
    return make_exercise(world.clinic)


def post(api: APIClient, patient, exercise, content: bytes, name: str = "take.bvh.gz"):
    data = {"patient": str(patient.pk), "file": SimpleUploadedFile(name, content)}
    if exercise is not None:
        data["exercise"] = str(exercise.pk)
    return api.post("/api/v1/recordings/", data, format="multipart")


def mismatched() -> bytes:
    return gzip.decompress(fixture_bytes(GOOD)).decode().replace("LeftFoot", "LeftPaw").encode()


@pytest.mark.parametrize(
    "case",
    [
        (b"HIERARCHY\nROOT Hips\n{\n", "broken.bvh", "not a readable BVH"),
        (b"\x00\x01\x02garbage", "take.bvh", "not a readable BVH"),
        (gzip.compress(b"MOTION\nFrames: 1\n"), "take.bvh.gz", "not a readable BVH"),
        (b"%PDF-1.4 not motion at all", "scan.pdf", "Upload a BVH"),
        (b"PNG\x89 image", "photo.png", "Upload a BVH"),
    ],
)
def test_bad_file_is_400_with_reason(api, world, exercise, settings, case):
    content, name, reason = case
    response = post(api, world.patient, exercise, content, name)
    assert response.status_code == 400
    assert reason in response.json()["file"][0]["message"]
    assert_nothing_stored(settings)


def test_oversize_is_400(api, world, exercise, settings):
    settings.MAX_UPLOAD_BYTES = 1000
    response = post(api, world.patient, exercise, fixture_bytes(GOOD))
    assert response.status_code == 400
    assert "largest accepted" in response.json()["file"][0]["message"]
    assert_nothing_stored(settings)


def test_skeleton_mismatch_is_400(api, world, exercise, settings):
    response = post(api, world.patient, exercise, mismatched(), "take.bvh")
    assert response.status_code == 400
    message = response.json()["file"][0]["message"]
    assert "skeleton does not match" in message and "left foot" in message
    assert_nothing_stored(settings)


def test_duplicate_is_400_and_keeps_the_first(api, world, exercise, monkeypatch):
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda run_id: None)
    assert post(api, world.patient, exercise, fixture_bytes(GOOD)).status_code == 201
    response = post(api, world.patient, exercise, fixture_bytes(GOOD))
    assert response.status_code == 400
    assert "already uploaded" in response.json()["file"][0]["message"]
    assert Recording.objects.count() == 1


@pytest.mark.parametrize(
    "case", [("patient", "not-a-uuid"), ("pain_score", "11"), ("exercise", "nope")]
)
def test_malformed_fields_are_400_not_500(api, world, exercise, settings, case):
    field, value = case
    data = {
        "patient": str(world.patient.pk),
        "exercise": str(exercise.pk),
        "file": SimpleUploadedFile("take.bvh.gz", fixture_bytes(GOOD)),
        field: value,
    }
    response = api.post("/api/v1/recordings/", data, format="multipart")
    assert response.status_code == 400
    assert field in response.json()
    assert_nothing_stored(settings)


def test_exercise_of_another_clinic_is_400(api, world, settings):
    elsewhere = make_exercise(world.other_clinic, name="Elsewhere")
    response = post(api, world.patient, elsewhere, fixture_bytes(GOOD))
    assert response.status_code == 400
    assert "exercise" in response.json()
    assert_nothing_stored(settings)


def test_unknown_patient_is_404(api, world, exercise, settings):
    data = {
        "patient": "00000000-0000-0000-0000-000000000000",
        "exercise": str(exercise.pk),
        "file": SimpleUploadedFile("take.bvh.gz", fixture_bytes(GOOD)),
    }
    assert api.post("/api/v1/recordings/", data, format="multipart").status_code == 404
    assert_nothing_stored(settings)


def test_failure_inside_the_transaction_leaves_no_file(world, exercise, settings, monkeypatch):
    from django.core.files.uploadedfile import SimpleUploadedFile as Upload

    from webapp.recordings.uploads import parse_upload, store_recording

    def broken(recording):
        raise RuntimeError("database went away")

    monkeypatch.setattr("webapp.recordings.services.start_analysis", broken)
    parsed = parse_upload(Upload("take.bvh.gz", fixture_bytes(GOOD)))
    with pytest.raises(RuntimeError):
        store_recording(parsed, patient=world.patient, exercise=exercise, user=world.therapist)
    assert_nothing_stored(settings)
