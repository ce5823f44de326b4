"""A worker "on another machine": a separate Celery process with an empty data folder of its own,
sharing only PostgreSQL, Redis and the bucket with the web process. It analyses an upload made
through the API; the upload, the model, the arrays and the result end up in the bucket and the
database, and no data file is written under either process's data folder."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from rest_framework.test import APIClient

from tests.personas import fixture_bytes, make_exercise, make_world
from tests.s3_server import files_under, s3_server  # noqa: F401  (fixture)
from tests.workers.conftest import Worker, needs_services
from webapp.recordings.models import AnalysisRun

pytestmark = [
    pytest.mark.integration,
    needs_services,
    pytest.mark.django_db(transaction=True),
    pytest.mark.timeout(120),
]


def wait_until_finished(run_id, worker: Worker, timeout: float = 60.0) -> AnalysisRun:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        run = AnalysisRun.objects.get(pk=run_id)
        if run.status in ("succeeded", "failed"):
            return run
        time.sleep(0.3)
    raise AssertionError("the analysis did not finish:\n" + worker.log())


def test_worker_with_its_own_empty_data_folder_analyses_from_the_bucket(
    s3_server,  # noqa: F811
    celery_queue,
    settings,
    tmp_path,
):
    settings.STORAGES = s3_server.storages()
    web_media = Path(settings.MEDIA_ROOT)
    remote_data = tmp_path / "remote-data"  # the other machine's DATA_DIR: empty, not shared
    remote = Worker(
        celery_queue,
        remote_data / "media",
        tmp_path / "remote-worker.log",
        {**s3_server.env(), "DATA_DIR": str(remote_data)},
    )
    remote.start()
    try:
        world = make_world()
        exercise = make_exercise(world.clinic)
        api = APIClient()
        api.force_authenticate(world.therapist)
        upload = {
            "patient": str(world.patient.pk),
            "exercise": str(exercise.pk),
            "file": SimpleUploadedFile("take.bvh.gz", fixture_bytes("reps/m01_s01_e02.bvh.gz")),
        }
        created = api.post("/api/v1/recordings/", upload, format="multipart")
        assert created.status_code == 201, created.content
        run = wait_until_finished(created.json()["run"]["id"], remote)
        assert run.status == "succeeded", (run.user_error, run.developer_error, remote.log())
        assert run.worker and "analyse_recording[" in remote.log()
        detail = api.get(f"/api/v1/recordings/{run.recording_id}/").json()
        assert detail["status"] == "succeeded" and detail["result"]["repetitions"]
    finally:
        remote.stop()

    keys = s3_server.object_names()
    assert run.recording.file.name in keys
    assert run.arrays.name in keys and run.arrays.name.startswith("runs/")
    assert any(key.startswith("models/") for key in keys), keys
    assert files_under(remote_data) == [], "the remote worker wrote into its data folder"
    assert files_under(web_media) == [], "the web process wrote into its data folder"
