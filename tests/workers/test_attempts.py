"""The attempt count and the limits' reasons, without a worker process: a run is claimed at most
`ANALYSIS_MAX_ATTEMPTS` times (a retry resuming its own lease is not a new attempt); a run whose
worker died under it that often fails with a plain reason whichever way it would come back (the
claim, the main process releasing it, `make run`'s resume); a MemoryError or the soft time limit
in an analysis, and the hard time limit, fail the run with a plain reason."""

from __future__ import annotations

import re
import subprocess
import sys
from datetime import timedelta
from pathlib import Path

import pytest
from billiard.exceptions import SoftTimeLimitExceeded, TimeLimitExceeded
from django.utils import timezone

from tests.personas import make_exercise, make_recording, make_world
from tests.workers.conftest import Worker, needs_services
from webapp.recordings.models import AnalysisRun, RunStatus
from workers import analysis_task, housekeeping, limits, runs, tasks
from workers.task_guard import AnalysisTask, run_id_of

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def run(db, settings):
    settings.ANALYSIS_MAX_ATTEMPTS = 2
    settings.ANALYSIS_LEASE_SECONDS = 60
    world = make_world()
    recording = make_recording(world.patient, make_exercise(world.clinic))
    return AnalysisRun.objects.get(recording=recording)


def abandon(run: AnalysisRun) -> None:
    """What a worker killed mid-analysis leaves: RUNNING, its heartbeat older than the lease."""
    AnalysisRun.objects.filter(pk=run.pk).update(
        status=RunStatus.RUNNING, heartbeat_at=timezone.now() - timedelta(seconds=120)
    )


def test_a_run_abandoned_twice_fails_at_the_third_claim_with_a_reason(run):
    first = runs.claim(str(run.pk), "w1")
    assert first and runs.claim(str(run.pk), "w2") is None, "a live lease is not taken"
    abandon(run)
    second = runs.claim(str(run.pk), "w2")
    assert second and second != first
    run.refresh_from_db()
    assert (run.status, run.attempts) == (RunStatus.RUNNING, 2)

    abandon(run)
    assert runs.claim(str(run.pk), "w3") is None
    run.refresh_from_db()
    assert run.status == RunStatus.FAILED and run.attempts == 2
    assert run.user_error == limits.died_too_often_message(2)
    assert "twice" in run.user_error and "will not help" in run.user_error
    assert run.lease_token == "" and run.finished_at is not None
    assert runs.claim(str(run.pk), "w4") is None and run.attempts == 2


def test_a_transient_retry_resuming_its_lease_is_not_a_new_attempt(run):
    token = runs.claim(str(run.pk), "w1")
    for _ in range(3):  # the database went away three times during one attempt
        token = runs.claim(str(run.pk), "w1", resume_token=token)
        assert token
    run.refresh_from_db()
    assert run.attempts == 1 and run.lease_token == token
    assert runs.claim(str(run.pk), "w1", resume_token="someone-else") is None


def test_the_main_process_releases_a_run_whose_pool_process_died(run):
    """Killed once: QUEUED again at once, so the message Celery puts back claims it (attempt 2)
    without waiting for the lease; killed again: it fails with the reason, never queued a third
    time."""
    runs.claim(str(run.pk), "w1")
    assert housekeeping.release_lost_run(str(run.pk)) == "queued"
    run.refresh_from_db()
    assert (run.status, run.lease_token, run.progress) == (RunStatus.QUEUED, "", 0)
    assert runs.claim(str(run.pk), "w1")
    assert housekeeping.release_lost_run(str(run.pk)) == "failed"
    run.refresh_from_db()
    assert run.status == RunStatus.FAILED and run.attempts == 2
    assert run.user_error == limits.died_too_often_message(2)
    assert housekeeping.release_lost_run(str(run.pk)) == ""


def test_make_runs_resume_fails_a_run_tried_twice_instead_of_queuing_it(run, settings, monkeypatch):
    sent: list[str] = []
    monkeypatch.setattr(tasks.analyse_recording, "delay", sent.append)
    settings.CELERY_BROKER_URL = "filesystem://"
    runs.claim(str(run.pk), "w1")  # the worker is killed mid-analysis; the launcher restarts it
    assert tasks.resume_interrupted_local_runs() == {"resumed": 1, "failed": 0}
    assert runs.claim(str(run.pk), "w2")  # ... and kills it again
    assert tasks.resume_interrupted_local_runs() == {"resumed": 0, "failed": 1}
    assert sent == [str(run.pk)], "queued again once, never a third time"
    run.refresh_from_db()
    assert run.status == RunStatus.FAILED and run.user_error == limits.died_too_often_message(2)


def test_the_hard_time_limit_fails_the_run_with_its_reason(run, settings):
    settings.ANALYSIS_TIME_LIMIT = 360
    runs.claim(str(run.pk), "w1")
    task = tasks.analyse_recording
    assert isinstance(task, AnalysisTask)
    # As Celery calls it in the worker's main process once it killed the pool process.
    task.on_failure(TimeLimitExceeded(360), "task-id", (str(run.pk),), {}, None)
    run.refresh_from_db()
    assert run.status == RunStatus.FAILED
    assert run.user_error == limits.time_limit_message(360)
    assert "6 minutes" in run.user_error and "will not help" in run.user_error
    assert run_id_of((), {"run_id": "abc", "token": None}) == "abc"


@pytest.mark.parametrize(
    ("error", "words"),
    [(MemoryError("Unable to allocate 11.4 GiB"), "more memory"),
     (SoftTimeLimitExceeded(), "took longer than the 5 minutes")],
)  # fmt: skip
def test_an_analysis_past_a_limit_fails_with_a_plain_reason(
    run, settings, monkeypatch, error, words
):
    """Raised where the pipeline runs (the memory ceiling's MemoryError, Celery's soft limit):
    the run fails with the limit's reason, not the generic "failed unexpectedly"."""
    settings.ANALYSIS_SOFT_TIME_LIMIT = 300

    def analyse(*args, **kwargs):
        raise error

    monkeypatch.setattr(analysis_task, "analyse", analyse)
    assert analysis_task.analyse_run(str(run.pk)) == "failed"
    run.refresh_from_db()
    assert run.status == RunStatus.FAILED and words in run.user_error
    assert run.user_error != analysis_task.GENERIC_FAILURE
    assert type(error).__name__ in run.developer_error


def test_the_memory_ceiling_turns_a_huge_allocation_into_memory_error(tmp_path):
    """In a process of its own (the ceiling cannot be lifted again): a 4 GiB array under a
    1 GiB ceiling raises MemoryError and the process carries on."""
    code = (
        "import numpy, resource\n"
        "from workers.limits import apply_memory_limit, memory_limit_bytes\n"
        "assert memory_limit_bytes() is None or memory_limit_bytes() > 2 ** 30\n"
        "print(apply_memory_limit(1024) == memory_limit_bytes() == 2 ** 30)\n"
        "try:\n"
        "    numpy.ones(2 ** 29)\n"
        "    print('allocated')\n"
        "except MemoryError:\n"
        "    print('MemoryError')\n"
        "print(numpy.ones(10 ** 6).sum() == 10 ** 6)\n"
        "print(apply_memory_limit(0))\n"
    )
    answer = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True,
        env={"PATH": "/usr/bin:/bin", "DJANGO_SETTINGS_MODULE": "webapp.settings"},
    )  # fmt: skip
    assert answer.stdout.split() == ["True", "MemoryError", "True", "None"]


@pytest.mark.integration
@needs_services
@pytest.mark.django_db(transaction=True)
def test_a_worker_on_redis_sets_its_own_ceiling_before_its_first_analysis(
    celery_queue, settings, tmp_path
):
    """A worker as on another machine (Redis, PostgreSQL; the solo pool runs tasks in the worker
    itself): the ceiling from its own environment is on it once it analysed, and it analyses."""
    from tests.workers.test_api_flow import TUTOR, token_client, upload, wait_for_status

    world = make_world()
    exercise = make_exercise(world.clinic, source=TUTOR)
    worker = Worker(celery_queue, Path(settings.MEDIA_ROOT), tmp_path / "worker.log",
                    {"ANALYSIS_MEMORY_LIMIT_MB": "2500"})  # fmt: skip
    worker.start()
    try:
        created = upload(token_client("therapist"), world.patient, exercise)
        body = wait_for_status(token_client("therapist"), created["id"], timeout=90)
        limits_text = Path(f"/proc/{worker.process.pid}/limits").read_text()
    finally:
        worker.stop()
    assert body["status"] == "succeeded", worker.log()
    ceiling = re.search(r"Max data size\s+(\S+)", limits_text).group(1)
    assert ceiling == str(2500 * 1024 * 1024), limits_text
