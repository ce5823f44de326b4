"""The REST API as CONTRACTS.md lists it: token auth, patients, exercises, uploads."""

from __future__ import annotations

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from rest_framework.test import APIClient

from tests.personas import PASSWORD, fixture_bytes, make_exercise, make_recording
from webapp.recordings.models import Recording


@pytest.fixture
def api(world) -> APIClient:
    client = APIClient()
    response = client.post(
        "/api/v1/auth/token/", {"username": "therapist", "password": PASSWORD}, format="json"
    )
    assert response.status_code == 200
    client.credentials(HTTP_AUTHORIZATION=f"Token {response.json()['token']}")
    return client


def test_token_refused_for_wrong_password(world):
    response = APIClient().post(
        "/api/v1/auth/token/", {"username": "therapist", "password": "wrong"}, format="json"
    )
    assert response.status_code == 400


def test_patient_list_is_scoped_to_the_clinic(api, world):
    body = api.get("/api/v1/patients/").json()
    names = {p["display_name"] for p in body["results"]}
    assert names == {"Ann Example", "Bob Example"}


def test_other_clinic_patient_is_404(api, world):
    assert api.get(f"/api/v1/patients/{world.outsider_patient.pk}/").status_code == 404


def test_exercises_listed(api, world):
    make_exercise(world.clinic)
    make_exercise(world.other_clinic, name="Elsewhere")
    body = api.get("/api/v1/exercises/").json()
    assert [e["name"] for e in body["results"]] == ["Deep squat"]


def test_upload_then_read_back(api, world, monkeypatch):
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda run_id: None)
    exercise = make_exercise(world.clinic)
    upload = SimpleUploadedFile("take.bvh.gz", fixture_bytes("reps/m01_s01_e02.bvh.gz"))
    response = api.post(
        "/api/v1/recordings/",
        {"patient": str(world.patient.pk), "exercise": str(exercise.pk), "file": upload},
        format="multipart",
    )
    assert response.status_code == 201, response.content
    body = response.json()
    assert body["status"] == "queued" and body["progress"] == 0 and body["result"] is None
    detail = api.get(f"/api/v1/recordings/{body['id']}/").json()
    assert detail["id"] == body["id"]


def test_upload_of_garbage_is_400_with_reason(api, world):
    exercise = make_exercise(world.clinic)
    upload = SimpleUploadedFile("take.bvh", b"not a bvh file")
    response = api.post(
        "/api/v1/recordings/",
        {"patient": str(world.patient.pk), "exercise": str(exercise.pk), "file": upload},
        format="multipart",
    )
    assert response.status_code == 400
    assert "BVH" in response.content.decode()
    assert Recording.objects.count() == 0


def test_upload_for_other_clinic_patient_is_404(api, world):
    exercise = make_exercise(world.clinic)
    upload = SimpleUploadedFile("take.bvh.gz", fixture_bytes("reps/m01_s01_e02.bvh.gz"))
    response = api.post(
        "/api/v1/recordings/",
        {"patient": str(world.outsider_patient.pk), "exercise": str(exercise.pk), "file": upload},
        format="multipart",
    )
    assert response.status_code == 404


def test_missing_fields_are_400(api, world):
    response = api.post("/api/v1/recordings/", {}, format="multipart")
    assert response.status_code == 400
    assert "patient" in response.json()


def test_progress_and_date_filter(api, world):
    exercise = make_exercise(world.clinic)
    make_recording(world.patient, exercise)
    url = f"/api/v1/patients/{world.patient.pk}/progress/"
    assert api.get(url).json()["points"] == []  # no succeeded run yet
    assert api.get(url + "?since=not-a-date").status_code == 400
    recordings = api.get(f"/api/v1/patients/{world.patient.pk}/recordings/?since=2000-01-01")
    assert recordings.json()["count"] == 1
    none = api.get(f"/api/v1/patients/{world.patient.pk}/recordings/?until=2000-01-01")
    assert none.json()["count"] == 0


def test_schema_and_docs_served(api):
    assert api.get("/api/schema/").status_code == 200
    docs = api.get("/api/docs/")
    assert docs.status_code == 200
    assert b"cdn" not in docs.content.lower()
