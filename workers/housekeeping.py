"""Periodic maintenance run by Celery beat."""

from __future__ import annotations

from datetime import timedelta

from django.conf import settings
from django.utils import timezone

from webapp.recordings.models import AnalysisRun, RunStatus

REAPED_USER_MESSAGE = "The analysis did not finish in time. Please start it again."


def reap_window_seconds() -> int:
    """How long a run may stay RUNNING before the reaper fails it.

    A worker killed mid-analysis leaves its message unacknowledged; the broker delivers it again
    after the visibility timeout and the redelivered task reclaims the run (its lease has expired)
    and finishes it. So the reaper waits past both the hard time limit and the visibility
    timeout (plus a minute): it only fails runs whose message was lost, not ones about to resume.
    """
    visibility = settings.CELERY_BROKER_TRANSPORT_OPTIONS.get("visibility_timeout", 0)
    return max(settings.ANALYSIS_TIME_LIMIT, int(visibility)) + 60


def reap_stuck_runs() -> int:
    """Mark runs RUNNING for longer than `reap_window_seconds` as FAILED with a reason.

    Failing it keeps nothing stuck; the user sees the reason and can re-run. A reclaimed run
    restarts its window (claim sets started_at). Returns the number of runs reaped.
    """
    cutoff = timezone.now() - timedelta(seconds=reap_window_seconds())
    return AnalysisRun.objects.filter(status=RunStatus.RUNNING, started_at__lt=cutoff).update(
        status=RunStatus.FAILED,
        finished_at=timezone.now(),
        user_error=REAPED_USER_MESSAGE,
        developer_error="reaped: RUNNING past the time limit and the broker's redelivery",
    )
