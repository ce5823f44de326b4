"""State changes of an analysis run, each one a conditional UPDATE.

QUEUED → RUNNING: `claim` succeeds for one worker only. A RUNNING run whose heartbeat is older than
the lease was abandoned (its worker died): the redelivered task may claim it again with a new token,
up to ``ANALYSIS_MAX_ATTEMPTS`` claims in all; then the run fails with a reason instead.
RUNNING → SUCCEEDED | FAILED: written only by the holder of the current token, so a run ends once.

Every way a run ends (`succeed`, `fail`, `give_up`, and `workers.housekeeping` for runs killed
by a time limit) then refreshes what is stored from the outcome, in the same call and in view:
the run's reading (its verdicts, pass count and statements: `webapp.recordings.reading`), the
patient's row of the dashboard's attention list and the run's progress point
(`webapp.dashboard.precompute.refresh_after_run`), so pages read them without recomputing.
"""

from __future__ import annotations

import uuid
from datetime import timedelta
from typing import Any

from django.conf import settings
from django.db.models import F, Q, QuerySet
from django.utils import timezone

from webapp.dashboard.precompute import refresh_after_run
from webapp.recordings.models import AnalysisRun, RunStatus
from workers.limits import died_too_often_message


def claim(run_id: str, worker: str, resume_token: str | None = None) -> str | None:
    """Take the run for this worker; return the lease token, or None if someone else has it.

    `resume_token`: the token of this task's earlier attempt (a retry after a transient error),
    which may take the run back at once, before its lease expires; that is not a new attempt.
    Every other claim counts one attempt: a run whose worker died under it
    ``ANALYSIS_MAX_ATTEMPTS`` times is not claimed again but fails with a reason (`give_up`).
    """
    now = timezone.now()
    token = uuid.uuid4().hex
    taken = {
        "status": RunStatus.RUNNING, "started_at": now, "heartbeat_at": now,
        "lease_token": token, "worker": worker[:200], "stage": "starting", "progress": 0,
    }  # fmt: skip
    runs = AnalysisRun.objects.filter(pk=run_id)
    if resume_token and runs.filter(status=RunStatus.RUNNING, lease_token=resume_token).update(
        **taken
    ):
        return token
    abandoned = now - timedelta(seconds=settings.ANALYSIS_LEASE_SECONDS)
    claimable = Q(status=RunStatus.QUEUED) | Q(status=RunStatus.RUNNING, heartbeat_at__lt=abandoned)
    fresh = Q(attempts__lt=max_attempts())
    if runs.filter(claimable & fresh).update(attempts=F("attempts") + 1, **taken) == 1:
        return token
    give_up(runs.filter(claimable))
    return None


def max_attempts() -> int:
    return int(getattr(settings, "ANALYSIS_MAX_ATTEMPTS", 2))


def give_up(runs: QuerySet[AnalysisRun]) -> int:
    """Fail, with a plain reason, the runs already tried `max_attempts` times; returns how many.

    An attempt that ended without finishing (its worker was killed, ran out of memory or time)
    is the only way a run gets here, so a third try would most likely bring a worker down again.
    """
    spent = runs.filter(attempts__gte=max_attempts())
    ids = [str(pk) for pk in spent.values_list("pk", flat=True)[:1000]]
    failed = spent.filter(pk__in=ids).update(
        status=RunStatus.FAILED,
        stage="failed",
        finished_at=timezone.now(),
        lease_token="",
        user_error=died_too_often_message(max_attempts()),
        developer_error=f"not claimed again: {max_attempts()} attempts ended unfinished",
    )
    for run_id in ids:
        refresh_after_run(run_id)
    return failed


def report(run_id: str, token: str, stage: str, progress: int) -> bool:
    """Record progress (and the heartbeat); False when the lease was lost."""
    return (
        AnalysisRun.objects.filter(pk=run_id, lease_token=token, status=RunStatus.RUNNING).update(
            stage=stage[:60], progress=max(0, min(100, progress)), heartbeat_at=timezone.now()
        )
        == 1
    )


def succeed(run_id: str, token: str, **fields: Any) -> bool:
    """RUNNING → SUCCEEDED with the result ``fields``, then refresh the dashboard's stored rows."""
    ended = _end(run_id, token, status=RunStatus.SUCCEEDED, progress=100, stage="done", **fields)
    if ended:
        refresh_after_run(run_id)
    return ended


def fail(run_id: str, token: str, user_error: str, developer_error: str) -> bool:
    """RUNNING → FAILED with its reasons, then refresh the dashboard's stored rows."""
    ended = _end(
        run_id,
        token,
        status=RunStatus.FAILED,
        stage="failed",
        user_error=user_error[:2000],
        developer_error=developer_error[:20000],
    )
    if ended:
        refresh_after_run(run_id)
    return ended


def _end(run_id: str, token: str, **fields: Any) -> bool:
    """The conditional UPDATE that ends a run held with ``token``; nothing else."""
    running = AnalysisRun.objects.filter(pk=run_id, lease_token=token, status=RunStatus.RUNNING)
    return running.update(finished_at=timezone.now(), heartbeat_at=timezone.now(), **fields) == 1
