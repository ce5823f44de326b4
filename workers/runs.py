"""State changes of an analysis run, each one a conditional UPDATE.

QUEUED → RUNNING: `claim` succeeds for one worker only. A RUNNING run whose heartbeat is older than
the lease was abandoned (its worker died): the redelivered task may claim it again with a new token.
RUNNING → SUCCEEDED | FAILED: written only by the holder of the current token, so a run ends once.
"""

from __future__ import annotations

import uuid
from datetime import timedelta
from typing import Any

from django.conf import settings
from django.db.models import F, Q
from django.utils import timezone

from webapp.dashboard.precompute import refresh_after_run
from webapp.recordings.models import AnalysisRun, RunStatus


def claim(run_id: str, worker: str, resume_token: str | None = None) -> str | None:
    """Take the run for this worker; return the lease token, or None if someone else has it.

    `resume_token`: the token of this task's earlier attempt (a retry after a transient error),
    which may take the run back at once, before its lease expires.
    """
    now = timezone.now()
    abandoned = now - timedelta(seconds=settings.ANALYSIS_LEASE_SECONDS)
    token = uuid.uuid4().hex
    claimable = Q(status=RunStatus.QUEUED) | Q(status=RunStatus.RUNNING, heartbeat_at__lt=abandoned)
    if resume_token:
        claimable |= Q(status=RunStatus.RUNNING, lease_token=resume_token)
    updated = AnalysisRun.objects.filter(claimable, pk=run_id).update(
        status=RunStatus.RUNNING,
        started_at=now,
        heartbeat_at=now,
        lease_token=token,
        worker=worker[:200],
        attempts=F("attempts") + 1,
        stage="starting",
        progress=0,
    )
    return token if updated == 1 else None


def report(run_id: str, token: str, stage: str, progress: int) -> bool:
    """Record progress (and the heartbeat); False when the lease was lost."""
    return (
        AnalysisRun.objects.filter(pk=run_id, lease_token=token, status=RunStatus.RUNNING).update(
            stage=stage[:60], progress=max(0, min(100, progress)), heartbeat_at=timezone.now()
        )
        == 1
    )


def succeed(run_id: str, token: str, **fields: Any) -> bool:
    return _finish(run_id, token, status=RunStatus.SUCCEEDED, progress=100, stage="done", **fields)


def fail(run_id: str, token: str, user_error: str, developer_error: str) -> bool:
    return _finish(
        run_id,
        token,
        status=RunStatus.FAILED,
        stage="failed",
        user_error=user_error[:2000],
        developer_error=developer_error[:20000],
    )


def _finish(run_id: str, token: str, **fields: Any) -> bool:
    running = AnalysisRun.objects.filter(pk=run_id, lease_token=token, status=RunStatus.RUNNING)
    finished = running.update(finished_at=timezone.now(), heartbeat_at=timezone.now(), **fields)
    if finished == 1:  # the stored attention list follows the outcome (on write)
        refresh_after_run(run_id)
    return finished == 1
