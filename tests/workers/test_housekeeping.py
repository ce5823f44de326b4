from datetime import timedelta

import pytest
from django.utils import timezone

from tests.personas import make_world
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from workers.housekeeping import (
    INTERRUPTED_TOO_OFTEN_MESSAGE,
    NEVER_STARTED_MESSAGE,
    REAPED_USER_MESSAGE,
    reap_stuck_runs,
    reap_window_seconds,
)
from workers.tasks import requeue_lost_runs


@pytest.fixture
def recording(db):
    world = make_world()
    return Recording.objects.create(clinic=world.clinic, patient=world.patient, checksum="c")


def test_reaper_fails_only_runs_past_the_limit(recording, settings):
    now = timezone.now()
    old = now - timedelta(seconds=reap_window_seconds() + 60)
    stuck = AnalysisRun.objects.create(
        recording=recording, status=RunStatus.RUNNING, started_at=old
    )
    fresh = AnalysisRun.objects.create(
        recording=recording, status=RunStatus.RUNNING, started_at=now
    )
    queued = AnalysisRun.objects.create(recording=recording, status=RunStatus.QUEUED)

    assert reap_stuck_runs() == 1

    stuck.refresh_from_db()
    fresh.refresh_from_db()
    queued.refresh_from_db()
    assert stuck.status == RunStatus.FAILED
    assert stuck.user_error == REAPED_USER_MESSAGE
    assert stuck.finished_at is not None
    assert fresh.status == RunStatus.RUNNING
    assert queued.status == RunStatus.QUEUED
    assert reap_stuck_runs() == 0


def test_reaper_leaves_killed_runs_to_the_redelivery(recording, settings):
    """Past the hard time limit but before the broker delivers the message again: a redelivered
    task will reclaim and finish it, so the reaper must not fail it first."""
    settings.CELERY_BROKER_TRANSPORT_OPTIONS = {"visibility_timeout": 720}
    settings.ANALYSIS_TIME_LIMIT = 360
    assert reap_window_seconds() == 780
    started = timezone.now() - timedelta(seconds=500)
    AnalysisRun.objects.create(recording=recording, status=RunStatus.RUNNING, started_at=started)
    assert reap_stuck_runs() == 0


def test_lost_queued_runs_are_enqueued_again_then_failed(recording, settings, monkeypatch):
    """A QUEUED run whose message vanished (broker restarted empty) is enqueued again; one
    that was enqueued `ANALYSIS_MAX_ENQUEUES` times already fails with a reason."""
    from workers import tasks

    sent: list[str] = []
    monkeypatch.setattr(tasks.analyse_recording, "delay", sent.append)
    settings.ANALYSIS_REQUEUE_AFTER_SECONDS = 600
    settings.ANALYSIS_MAX_ENQUEUES = 3
    long_ago = timezone.now() - timedelta(seconds=700)
    lost = AnalysisRun.objects.create(recording=recording, enqueued_at=long_ago)
    hopeless = AnalysisRun.objects.create(
        recording=recording, enqueued_at=long_ago, enqueue_count=3
    )
    waiting = AnalysisRun.objects.create(recording=recording)

    assert requeue_lost_runs() == {"requeued": 1, "failed": 1}
    assert sent == [str(lost.pk)]
    lost.refresh_from_db()
    hopeless.refresh_from_db()
    waiting.refresh_from_db()
    assert lost.status == RunStatus.QUEUED and lost.enqueue_count == 2
    assert hopeless.status == RunStatus.FAILED and hopeless.user_error == NEVER_STARTED_MESSAGE
    assert waiting.status == RunStatus.QUEUED and waiting.enqueue_count == 1
    assert requeue_lost_runs() == {"requeued": 0, "failed": 0}


def test_make_runs_worker_queues_again_what_the_last_one_left_unfinished(
    recording, settings, monkeypatch
):
    """Under `make run` (the folder broker) a starting worker puts RUNNING runs back in the queue
    and enqueues them; one interrupted `ANALYSIS_MAX_ENQUEUES` times fails with a reason; finished
    and waiting runs are left alone. With any other broker it does nothing."""
    from workers import tasks

    sent: list[str] = []
    monkeypatch.setattr(tasks.analyse_recording, "delay", sent.append)
    settings.ANALYSIS_MAX_ENQUEUES = 3
    cut_short = AnalysisRun.objects.create(
        recording=recording, status=RunStatus.RUNNING, started_at=timezone.now(),
        stage="aligning", progress=60, lease_token="old-worker",
    )  # fmt: skip
    too_often = AnalysisRun.objects.create(
        recording=recording, status=RunStatus.RUNNING, enqueue_count=3
    )
    done = AnalysisRun.objects.create(recording=recording, status=RunStatus.SUCCEEDED)
    waiting = AnalysisRun.objects.create(recording=recording)

    settings.CELERY_BROKER_URL = "redis://127.0.0.1:6379/0"
    assert tasks.resume_interrupted_local_runs() is None  # a broker that redelivers by itself
    assert sent == []

    settings.CELERY_BROKER_URL = "filesystem://"
    assert tasks.resume_interrupted_local_runs() == {"resumed": 1, "failed": 1}
    assert sent == [str(cut_short.pk)]
    for run in (cut_short, too_often, done, waiting):
        run.refresh_from_db()
    assert cut_short.status == RunStatus.QUEUED and cut_short.enqueue_count == 2
    assert (cut_short.progress, cut_short.lease_token) == (0, "")
    assert too_often.status == RunStatus.FAILED
    assert too_often.user_error == INTERRUPTED_TOO_OFTEN_MESSAGE
    assert done.status == RunStatus.SUCCEEDED
    assert waiting.status == RunStatus.QUEUED and waiting.enqueue_count == 1
    assert tasks.resume_interrupted_local_runs() == {"resumed": 0, "failed": 0}
