"""Faults while recordings are being analysed: the broker restarts empty, the database goes away
for a few seconds. Every accepted recording must end analysed exactly once (one run, one claim
that finished, one arrays file) or failed with a reason; the reaper then finds nothing stuck.

The broker here is a redis-server of the test's own on a spare port, keeping nothing on disk, so
killing it loses every message queued in it. The database outage is a TCP proxy between the
worker and PostgreSQL that the test cuts: open connections drop, new ones are refused.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from django.db import connection

from tests.personas import make_exercise, make_world
from tests.workers.conftest import Worker, needs_services
from tests.workers.faults import RedisServer, TcpProxy, broker, free_port
from tests.workers.test_api_flow import TUTOR, token_client, upload
from tests.workers.test_worker_crash import stored_arrays
from webapp.patients.models import Patient, PerformanceLevel
from webapp.recordings.models import AnalysisRun, RunStatus
from workers.housekeeping import reap_stuck_runs
from workers.tasks import requeue_lost_runs

pytestmark = [pytest.mark.integration, needs_services, pytest.mark.django_db(transaction=True)]

UNFINISHED = {RunStatus.QUEUED, RunStatus.RUNNING}


def patients(world, count: int) -> list[Patient]:
    """Different patients, so the same file is not refused as a duplicate upload."""
    return [
        Patient.objects.create(clinic=world.clinic, display_name=f"Fault patient {i}")
        for i in range(count)
    ]


def wait_until(condition, timeout: float, message) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        time.sleep(0.2)
    raise AssertionError(message())


def runs_of(recording_ids: list[str]) -> list[AnalysisRun]:
    return list(AnalysisRun.objects.filter(recording_id__in=recording_ids))


def all_finished(recording_ids: list[str]) -> bool:
    return not any(run.status in UNFINISHED for run in runs_of(recording_ids))


def assert_each_analysed_once(recording_ids: list[str], media: Path, worker: Worker) -> None:
    runs = runs_of(recording_ids)
    assert sorted(str(run.recording_id) for run in runs) == sorted(recording_ids)  # one run each
    for run in runs:
        assert run.status == RunStatus.SUCCEEDED, (run.status, run.developer_error, worker.log())
        assert run.progress == 100 and run.arrays.name
    assert len(stored_arrays(media)) == len(recording_ids), "one arrays file per run, no orphan"
    levels = PerformanceLevel.objects.values_list("patient_id", "exercise_id", "joint")
    assert len(levels) == len(set(levels)) > 0
    outcome(runs)


def outcome(runs: list[AnalysisRun]) -> None:
    """One line for docs/sections/reliability_faults.md (shown with `pytest -s`)."""
    statuses = [run.status for run in runs]
    print(
        f"\nFAULT OUTCOME recordings={len(runs)} succeeded={statuses.count('succeeded')} "
        f"failed={statuses.count('failed')} attempts={[run.attempts for run in runs]} "
        f"enqueues={[run.enqueue_count for run in runs]}"
    )


def assert_nothing_stuck(settings) -> None:
    """The beat tasks, run now, find nothing to reap or re-enqueue: none stuck, none lost."""
    settings.ANALYSIS_REQUEUE_AFTER_SECONDS = 0
    assert reap_stuck_runs() == 0
    assert requeue_lost_runs() == {"requeued": 0, "failed": 0}
    assert not AnalysisRun.objects.filter(status__in=UNFINISHED).exists()


def test_redis_restarted_empty_while_runs_are_queued(celery_queue, settings, tmp_path):
    world = make_world()
    exercise = make_exercise(world.clinic, source=TUTOR)
    client = token_client("therapist")
    media = Path(settings.MEDIA_ROOT)
    redis = RedisServer(tmp_path / "redis", free_port(6390))
    redis.start()
    worker = Worker(
        celery_queue,
        media,
        tmp_path / "worker.log",
        {"REDIS_URL": redis.url, "ANALYSIS_STAGE_DELAY_SECONDS": "0.05"},
    )
    try:
        with broker(redis.url):
            worker.start()
            people = patients(world, 4)
            ids = [upload(client, person, exercise)["id"] for person in people[:3]]
            wait_until(
                lambda: AnalysisRun.objects.filter(status=RunStatus.RUNNING).exists(),
                60,
                worker.log,
            )
            waiting = redis.queue_length(celery_queue)
            assert waiting == 2, "two messages wait in Redis behind the running one"
            redis.kill()
            # Accepted while the broker is down: stored, its run QUEUED, the enqueue failed.
            ids.append(upload(client, people[3], exercise)["id"])
            redis.start()  # empty: the two queued messages (and the fourth's) are gone
            wait_until(
                lambda: AnalysisRun.objects.filter(status=RunStatus.SUCCEEDED).count() == 1,
                60,
                worker.log,
            )
            time.sleep(1.0)
            lost = AnalysisRun.objects.filter(status=RunStatus.QUEUED).count()
            assert lost == 3 and redis.queue_length(celery_queue) == 0, worker.log()

            settings.ANALYSIS_REQUEUE_AFTER_SECONDS = 0
            assert requeue_lost_runs() == {"requeued": 3, "failed": 0}
            wait_until(lambda: all_finished(ids), 90, worker.log)
    finally:
        worker.stop()
        redis.kill()
    assert_each_analysed_once(ids, media, worker)
    assert [run.attempts for run in runs_of(ids)] == [1, 1, 1, 1], "each claimed exactly once"
    assert sorted(run.enqueue_count for run in runs_of(ids)) == [1, 2, 2, 2]
    assert_nothing_stuck(settings)


def test_database_unavailable_for_a_few_seconds(celery_queue, settings, tmp_path):
    world = make_world()
    exercise = make_exercise(world.clinic, source=TUTOR)
    client = token_client("therapist")
    media = Path(settings.MEDIA_ROOT)
    params = connection.settings_dict
    proxy = TcpProxy((params.get("HOST") or "127.0.0.1", int(params.get("PORT") or 5432)))
    user = params.get("USER") or "postgres"
    through_proxy = f"postgres://{user}@127.0.0.1:{proxy.port}/{params['NAME']}"
    worker = Worker(
        celery_queue,
        media,
        tmp_path / "worker.log",
        {"DATABASE_URL": through_proxy, "ANALYSIS_STAGE_DELAY_SECONDS": "0.15"},
    )
    worker.start()
    try:
        ids = [upload(client, person, exercise)["id"] for person in patients(world, 2)]
        wait_until(
            lambda: AnalysisRun.objects.filter(status=RunStatus.RUNNING, progress__gte=20).exists(),
            60,
            worker.log,
        )
        proxy.cut()
        time.sleep(3.0)
        proxy.restore()
        wait_until(lambda: all_finished(ids), 90, worker.log)
    finally:
        worker.stop()
        proxy.close()
    log = worker.log()
    assert "interrupted, will retry" in log and "retry: Retry in" in log, log
    assert_each_analysed_once(ids, media, worker)
    assert_nothing_stuck(settings)
