from datetime import timedelta

import pytest
from django.utils import timezone

from tests.personas import make_world
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from workers.housekeeping import REAPED_USER_MESSAGE, reap_stuck_runs


@pytest.fixture
def recording(db):
    world = make_world()
    return Recording.objects.create(clinic=world.clinic, patient=world.patient, checksum="c")


def test_reaper_fails_only_runs_past_the_limit(recording, settings):
    now = timezone.now()
    old = now - timedelta(seconds=settings.ANALYSIS_TIME_LIMIT + 120)
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
