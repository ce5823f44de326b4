"""A real worker process, on Redis and PostgreSQL, runs a real task (not eager)."""

from __future__ import annotations

import time
from hashlib import sha256
from pathlib import Path

import pytest
from django.core.files.base import ContentFile

from tests.personas import make_world
from tests.workers.conftest import needs_services
from webapp.recordings.models import Recording
from workers.tasks import inspect_recording

FIXTURE = Path(__file__).resolve().parents[2] / "data" / "ui-prmd" / "reps" / "m01_s01_e01.bvh.gz"

pytestmark = [pytest.mark.integration, needs_services, pytest.mark.django_db(transaction=True)]


def make_recording() -> Recording:
    world = make_world()
    recording = Recording(
        clinic=world.clinic,
        patient=world.patient,
        checksum=sha256(FIXTURE.read_bytes()).hexdigest(),
        uploaded_by=world.therapist,
    )
    recording.file.save("m01.bvh.gz", ContentFile(FIXTURE.read_bytes()), save=True)
    return recording


def test_worker_process_inspects_a_recording(worker):
    recording = make_recording()
    result = inspect_recording.delay(str(recording.pk)).get(timeout=60)
    assert result["n_frames"] == 73
    assert result["n_joints"] == 22
    recording.refresh_from_db()
    assert recording.n_frames == 73
    assert recording.fps == pytest.approx(30.0, rel=1e-3)
    # The result reaches us through Redis before the worker's log line is flushed: wait for it.
    deadline = time.monotonic() + 10
    while "succeeded" not in worker.log() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert "inspect_recording[" in worker.log() and "succeeded" in worker.log()


def test_task_message_is_json(celery_queue):
    from workers import app

    assert app.conf.task_serializer == "json"
    assert app.conf.accept_content == ["json"]
    assert app.conf.task_acks_late is True
    assert app.conf.task_reject_on_worker_lost is True
    assert app.conf.task_time_limit > app.conf.task_soft_time_limit > 0
