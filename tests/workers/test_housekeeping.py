from datetime import timedelta

import pytest
from django.utils import timezone

from tests.personas import make_world
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from workers.housekeeping import REAPED_USER_MESSAGE, reap_stuck_runs, reap_window_seconds


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
