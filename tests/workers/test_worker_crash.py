"""Killing the worker (SIGKILL) in the middle of an analysis and starting it again finishes the
run once, with one result.

How it recovers: the task is acknowledged late, so the killed worker's message stays unacknowledged
in Redis and is delivered again once the visibility timeout has passed; the run's lease (its
heartbeat) has expired by then, so the redelivered task may claim it with a new token. The test
shortens both through the worker's environment and slows each pipeline stage so it can kill the
worker while the analysis is running.
"""

from __future__ import annotations

import signal
import time
from pathlib import Path

import pytest
from rest_framework.test import APIClient

from tests.personas import make_exercise, make_world
from tests.workers.conftest import Worker, needs_services
from tests.workers.test_api_flow import TUTOR, token_client, upload, wait_for_status
from webapp.patients.models import PerformanceLevel
from webapp.recordings.models import AnalysisRun, RunStatus

pytestmark = [pytest.mark.integration, needs_services, pytest.mark.django_db(transaction=True)]

SHORT = {"ANALYSIS_LEASE_SECONDS": "2", "BROKER_VISIBILITY_TIMEOUT": "3"}


def wait_until_mid_analysis(run: AnalysisRun, worker: Worker, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        run.refresh_from_db()
        if run.status == RunStatus.RUNNING and run.progress >= 20:
            return
        assert run.status in {RunStatus.QUEUED, RunStatus.RUNNING}, (run.status, worker.log())
        time.sleep(0.1)
    raise AssertionError("the analysis never got going:\n" + worker.log())


def stored_arrays(media_root: Path) -> list[Path]:
    return sorted((media_root / "runs").rglob("*.npz")) if (media_root / "runs").exists() else []


def test_sigkill_mid_analysis_then_restart_finishes_once(celery_queue, settings, tmp_path):
    world = make_world()
    exercise = make_exercise(world.clinic, source=TUTOR)
    client: APIClient = token_client("therapist")
    media = Path(settings.MEDIA_ROOT)
    first = Worker(
        celery_queue,
        media,
        tmp_path / "first.log",
        {**SHORT, "ANALYSIS_STAGE_DELAY_SECONDS": "1.5"},
    )
    first.start()
    try:
        created = upload(client, world.patient, exercise)
        run = AnalysisRun.objects.get(recording_id=created["id"])
        wait_until_mid_analysis(run, first)
        first.kill(signal.SIGKILL)
    finally:
        first.stop()
    run.refresh_from_db()
    assert run.status == RunStatus.RUNNING and run.attempts == 1
    assert stored_arrays(media) == []
    time.sleep(3.5)  # past the visibility timeout and the lease

    second = Worker(celery_queue, media, tmp_path / "second.log", SHORT)
    second.start()
    try:
        body = wait_for_status(client, created["id"], timeout=60)
        time.sleep(1.0)  # a duplicate delivery, if any, would run now
    finally:
        second.stop()
    assert body["status"] == "succeeded", second.log()
    run.refresh_from_db()
    assert AnalysisRun.objects.filter(recording_id=created["id"]).count() == 1
    assert run.attempts == 2 and run.progress == 100
    assert len(stored_arrays(media)) == 1
    joints = PerformanceLevel.objects.filter(patient=world.patient, exercise=exercise)
    assert joints.count() == len(set(joints.values_list("joint", flat=True))) > 0
    assert second.log().count("analyse_recording[") >= 1
    assert "'skipped'" not in second.log()
