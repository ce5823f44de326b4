"""The done-when flow: upload through the API, a real worker process analyses it on Redis and
PostgreSQL, the API answers `succeeded` with the result fields of the interface contract."""

from __future__ import annotations

import time

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from rest_framework.test import APIClient

from tests.personas import PASSWORD, fixture_bytes, make_exercise, make_world
from tests.workers.conftest import needs_services
from webapp.patients.models import PerformanceLevel
from webapp.recordings.models import AnalysisRun

pytestmark = [pytest.mark.integration, needs_services, pytest.mark.django_db(transaction=True)]

TUTOR = "sessions/m01_s01_correct.bvh.gz"
RECORDING = "sessions/m01_s01_incorrect.bvh.gz"
RESULT_FIELDS = {
    "frames",
    "fps",
    "landmarks",
    "repetitions",
    "score",
    "assessment",
    "feedback",
    "timings_ms",
}


def token_client(username: str) -> APIClient:
    client = APIClient()
    answer = client.post(
        "/api/v1/auth/token/", {"username": username, "password": PASSWORD}, format="json"
    )
    client.credentials(HTTP_AUTHORIZATION=f"Token {answer.json()['token']}")
    return client


def upload(client: APIClient, patient, exercise, source: str = RECORDING) -> dict:
    response = client.post(
        "/api/v1/recordings/",
        {
            "patient": str(patient.pk),
            "exercise": str(exercise.pk),
            "file": SimpleUploadedFile("session.bvh.gz", fixture_bytes(source)),
        },
        format="multipart",
    )
    assert response.status_code == 201, response.content
    return response.json()


def wait_for_status(client: APIClient, recording_id: str, timeout: float = 90.0) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        body = client.get(f"/api/v1/recordings/{recording_id}/").json()
        if body["status"] in {"succeeded", "failed"}:
            return body
        time.sleep(0.3)
    raise AssertionError(f"analysis did not finish: {body}")


def test_upload_through_the_api_is_analysed_by_the_worker(worker):
    world = make_world()
    exercise = make_exercise(world.clinic, source=TUTOR)
    client = token_client("therapist")
    created = upload(client, world.patient, exercise)
    # A quick worker may already have claimed the run when the answer is serialised.
    assert created["status"] in {"queued", "running"}
    body = wait_for_status(client, created["id"])
    assert body["status"] == "succeeded", (body, worker.log())
    assert body["progress"] == 100
    result = body["result"]
    assert set(result) >= RESULT_FIELDS
    assert result["frames"] == 1044 and result["fps"] == pytest.approx(30.0, rel=1e-3)
    assert result["repetitions"], "a ten-repetition session has repetitions"
    assert all(0 <= rep["score"] <= 100 for rep in result["repetitions"])
    assert 0 <= result["score"] <= 100
    assert {"frame", "type", "levels"} <= set(result["assessment"][0])
    run = AnalysisRun.objects.get(recording_id=created["id"])
    assert run.model is not None and run.code_version and run.attempts == 1
    assert run.arrays.name.endswith(".npz") and run.arrays.storage.exists(run.arrays.name)
    assert PerformanceLevel.objects.filter(patient=world.patient, exercise=exercise).exists()
    # The patient reads their own result; a therapist of another clinic does not see it.
    assert token_client("patient").get(f"/api/v1/recordings/{created['id']}/").status_code == 200
    assert token_client("outsider").get(f"/api/v1/recordings/{created['id']}/").status_code == 404
