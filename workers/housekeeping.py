"""Periodic maintenance run by Celery beat."""

from __future__ import annotations

import logging
from collections.abc import Callable
from datetime import timedelta
from typing import Any

from django.conf import settings
from django.db import transaction
from django.db.models import F, QuerySet
from django.utils import timezone

from webapp.dashboard.precompute import refresh_after_run
from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from workers.limits import time_limit_message
from workers.runs import give_up

log = logging.getLogger(__name__)
REAPED_USER_MESSAGE = "The analysis did not finish in time. Please start it again."
INTERRUPTED_TOO_OFTEN_MESSAGE = (
    "The analysis was interrupted several times (the analysis service stopped while it ran). "
    "Please start it again; if it keeps happening, tell your administrator."
)
NEVER_STARTED_MESSAGE = (
    "The analysis could not be started: the task queue lost it several times. Please start it "
    "again; if it keeps happening, tell your administrator."
)


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


def requeue_after_seconds() -> int:
    """How long a run may stay QUEUED before its message is presumed lost (Redis restarted empty).

    Enqueuing again a message that was not lost is harmless (only one task can claim the run), so
    the window only has to be longer than the usual wait in the queue.
    """
    return int(getattr(settings, "ANALYSIS_REQUEUE_AFTER_SECONDS", 600))


def max_enqueues() -> int:
    return int(getattr(settings, "ANALYSIS_MAX_ENQUEUES", 4))


def _fail(runs: QuerySet[AnalysisRun], user_error: str, developer_error: str) -> int:
    """Fail the runs with a reason for the user and one for the team; returns how many."""
    return runs.update(
        status=RunStatus.FAILED,
        stage="failed",
        finished_at=timezone.now(),
        user_error=user_error,
        developer_error=developer_error,
    )


def _enqueue_again(
    runs: QuerySet[AnalysisRun], enqueue: Callable[[str], object], **changes: Any
) -> int:
    """Enqueue each of the runs (up to 1,000) that a conditional update takes, counting the
    enqueue: the query is the condition, so two callers never both enqueue one run."""
    count = 0
    for run_id in runs.values_list("pk", flat=True)[:1000]:
        taken = runs.filter(pk=run_id).update(
            enqueued_at=timezone.now(), enqueue_count=F("enqueue_count") + 1, **changes
        )
        if taken:
            enqueue(str(run_id))
            count += 1
    return count


def requeue_lost_runs(enqueue: Callable[[str], object]) -> dict[str, int]:
    """Enqueue again QUEUED runs not started within `requeue_after_seconds`; after
    `max_enqueues` attempts fail them with a reason instead. Returns both counts.

    `enqueue(run_id)` hands a run to the broker (the task module passes the analysis task's).
    """
    cutoff = timezone.now() - timedelta(seconds=requeue_after_seconds())
    stale = AnalysisRun.objects.filter(status=RunStatus.QUEUED, enqueued_at__lt=cutoff)
    failed = _fail(
        stale.filter(enqueue_count__gte=max_enqueues()),
        NEVER_STARTED_MESSAGE,
        f"never claimed after {max_enqueues()} enqueues",
    )
    return {"requeued": _enqueue_again(stale, enqueue), "failed": failed}


def resume_interrupted_runs(enqueue: Callable[[str], object]) -> dict[str, int]:
    """Put back in the queue the runs a worker left RUNNING when it ended; for `make run`'s one
    worker only (workers/local.py), called as it starts, when no analysis can be under way.

    Its folder transport removes a message when a worker takes it, so an analysis cut short
    (`make run` stopped, the worker killed or out of memory) is delivered by nothing else; the
    reaper would fail it after the time limit. A run already tried ``ANALYSIS_MAX_ATTEMPTS``
    times (or enqueued `max_enqueues` times) fails with a reason instead, so an analysis that
    brings the worker down is never queued a third time.
    """
    running = AnalysisRun.objects.filter(status=RunStatus.RUNNING)
    failed = give_up(running)  # its worker died under it ANALYSIS_MAX_ATTEMPTS times
    failed += _fail(
        running.filter(enqueue_count__gte=max_enqueues()),
        INTERRUPTED_TOO_OFTEN_MESSAGE,
        f"interrupted after {max_enqueues()} enqueues",
    )
    resumed = _enqueue_again(running, enqueue, status=RunStatus.QUEUED, stage="", progress=0,
                             lease_token="")  # fmt: skip
    if resumed or failed:
        log.info("interrupted analyses: %d queued again, %d failed", resumed, failed)
    return {"resumed": resumed, "failed": failed}


def release_lost_run(run_id: str) -> str:
    """The pool process analysing the run died (killed, out of memory): called by the worker's
    main process before the message goes back to the queue. The run is QUEUED again at once (its
    lease is the dead process's), or fails with a reason when it was its last attempt. Returns
    "failed", "queued" or "" (the run was not RUNNING)."""
    running = AnalysisRun.objects.filter(pk=run_id, status=RunStatus.RUNNING)
    if give_up(running):
        return "failed"
    queued = running.update(status=RunStatus.QUEUED, stage="", progress=0, lease_token="")
    return "queued" if queued else ""


def fail_timed_out(run_id: str, seconds: float) -> bool:
    """The hard time limit killed the pool process analysing the run: fail it with its reason
    (called by the worker's main process; the message is not delivered again)."""
    failed = _fail(
        AnalysisRun.objects.filter(pk=run_id, status=RunStatus.RUNNING),
        time_limit_message(seconds),
        f"hard time limit ({seconds:.0f} s): the pool process was killed",
    )
    if failed:
        refresh_after_run(run_id)
    return failed == 1


def purge_deleted_patients(now=None) -> int:
    """Hard-delete patients soft-deleted more than PATIENT_RETENTION_DAYS ago.

    Their prescriptions, levels, recordings and runs go with them (cascade); the stored files
    (uploads and result arrays) are deleted once the rows are gone. Returns the patients purged.
    """
    purged = 0
    for patient in Patient.all_objects.past_retention(now):
        patient_id, files = patient.pk, stored_files(patient)
        with transaction.atomic():
            patient.hard_delete()
        delete_files(files)
        log.info("purged patient %s and %d files", patient_id, len(files))
        purged += 1
    return purged


def stored_files(patient: Patient) -> list[tuple[object, str]]:
    recordings = Recording.all_objects.filter(patient=patient)
    files = [(r.file.storage, r.file.name) for r in recordings if r.file.name]
    runs = AnalysisRun.objects.filter(recording__in=recordings).exclude(arrays="")
    files += [(run.arrays.storage, run.arrays.name) for run in runs]
    return files


def delete_files(files: list[tuple[object, str]]) -> None:
    for storage, name in files:
        try:
            storage.delete(name)  # type: ignore[attr-defined]
        except OSError:
            log.warning("could not delete purged file %s", name, exc_info=True)
