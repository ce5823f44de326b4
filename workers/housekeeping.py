"""Periodic maintenance run by Celery beat."""

from __future__ import annotations

from datetime import timedelta

from django.conf import settings
from django.utils import timezone

from webapp.recordings.models import AnalysisRun, RunStatus

REAPED_USER_MESSAGE = "The analysis did not finish in time. Please start it again."


def reap_stuck_runs() -> int:
    """Mark runs RUNNING for longer than the hard time limit (plus a margin) as FAILED.

    The hard limit kills a task that overruns, so a run still RUNNING after it has lost its
    worker (killed, machine gone). Failing it with a reason keeps nothing stuck; the user can
    re-run. Returns the number of runs reaped.
    """
    margin = timedelta(seconds=settings.ANALYSIS_TIME_LIMIT + 60)
    cutoff = timezone.now() - margin
    return AnalysisRun.objects.filter(status=RunStatus.RUNNING, started_at__lt=cutoff).update(
        status=RunStatus.FAILED,
        finished_at=timezone.now(),
        user_error=REAPED_USER_MESSAGE,
        developer_error="reaped: RUNNING past ANALYSIS_TIME_LIMIT",
    )
