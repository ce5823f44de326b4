"""With S3_BUCKET set, every file goes to the bucket through the S3 API: the upload, the result
arrays, the exercise model and the PDF report; nothing is written under the data folder.

The bucket lives on a real S3-compatible server (moto's server mode) in another process.
"""

from __future__ import annotations

import io
import time

import numpy as np
import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.test import Client
from django.urls import reverse
from rest_framework.test import APIClient

from tests.personas import fixture_bytes, make_exercise
from tests.s3_server import files_under, s3_server  # noqa: F401  (fixture)
from webapp.recordings.models import Recording
from webapp.recordings.storage_backup import backup

pytestmark = pytest.mark.timeout(120)


@pytest.fixture
def bucket(s3_server, settings):  # noqa: F811
    settings.STORAGES = s3_server.storages()
    settings.S3_BUCKET = s3_server.bucket
    return s3_server


def test_settings_choose_s3_when_a_bucket_is_named(monkeypatch):
    import importlib

    import webapp.settings as module

    monkeypatch.setenv("S3_BUCKET", "clinic-files")
    monkeypatch.setenv("S3_ENDPOINT_URL", "http://minio:9000")
    try:
        fresh = importlib.reload(module)
        default = fresh.STORAGES["default"]
        assert default["BACKEND"] == "storages.backends.s3.S3Storage"
        assert default["OPTIONS"]["bucket_name"] == "clinic-files"
        assert default["OPTIONS"]["endpoint_url"] == "http://minio:9000"
        assert default["OPTIONS"]["file_overwrite"] is False
    finally:
        monkeypatch.delenv("S3_BUCKET")
        monkeypatch.delenv("S3_ENDPOINT_URL")
        fresh = importlib.reload(module)
    assert fresh.STORAGES["default"]["BACKEND"].endswith("FileSystemStorage")


def test_upload_analysis_model_and_report_are_in_the_bucket(
    bucket, world, settings, tmp_path, django_capture_on_commit_callbacks
):
    started = time.monotonic()
    exercise = make_exercise(world.clinic)
    api = APIClient()
    api.force_authenticate(world.therapist)
    data = {
        "patient": str(world.patient.pk),
        "exercise": str(exercise.pk),
        "file": SimpleUploadedFile("take.bvh.gz", fixture_bytes("reps/m01_s01_e02.bvh.gz")),
    }
    with django_capture_on_commit_callbacks(execute=True):  # the analysis, in-process (eager)
        created = api.post("/api/v1/recordings/", data, format="multipart")
    assert created.status_code == 201, created.content
    detail = api.get(f"/api/v1/recordings/{created.json()['id']}/").json()
    assert detail["status"] == "succeeded", detail
    assert detail["result"]["repetitions"] and "score" in detail["result"]

    recording = Recording.objects.get(pk=detail["id"])
    run = recording.runs.first()
    keys = bucket.object_names()
    assert recording.file.name in keys and recording.file.name.startswith("recordings/")
    assert run.arrays.name in keys and run.arrays.name.endswith(".npz")
    assert exercise.tutor_file.name in keys
    assert any(key.startswith("models/") for key in keys), keys
    body = bucket.client().get_object(Bucket=bucket.bucket, Key=run.arrays.name)["Body"].read()
    with np.load(io.BytesIO(body)) as arrays:
        assert len(arrays.files) > 0

    from workers.tasks import make_report

    name = make_report.delay("recording", str(recording.pk), "reports/r.pdf").get()
    assert name in bucket.object_names()
    page = api.get(f"/api/v1/recordings/{recording.pk}/result/")
    assert page.status_code == 200
    client = Client()
    client.force_login(world.therapist)
    playback = client.get(reverse("reports:playback", kwargs={"pk": recording.pk}))
    assert playback.status_code == 200 and playback.json()["available"] is True  # arrays read back
    manifest = backup(tmp_path / "backup.tar.gz")  # backs up the bucket, not a folder
    assert sorted(manifest["files"]) == bucket.object_names()
    assert files_under(settings.MEDIA_ROOT) == []
    assert time.monotonic() - started < 60
