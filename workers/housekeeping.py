"""Periodic maintenance run by Celery beat."""

from __future__ import annotations

import logging
from collections.abc import Callable
from datetime import timedelta

from django.conf import settings
from django.db import transaction
from django.db.models import F
from django.utils import timezone

from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun, Recording, RunStatus

log = logging.getLogger(__name__)
REAPED_USER_MESSAGE = "The analysis did not finish in time. Please start it again."
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


def requeue_lost_runs(enqueue: Callable[[str], object]) -> dict[str, int]:
    """Enqueue again QUEUED runs not started within `requeue_after_seconds`; after
    `max_enqueues` attempts fail them with a reason instead. Returns both counts.

    `enqueue(run_id)` hands a run to the broker (the task module passes the analysis task's).
    """
    cutoff = timezone.now() - timedelta(seconds=requeue_after_seconds())
    stale = AnalysisRun.objects.filter(status=RunStatus.QUEUED, enqueued_at__lt=cutoff)
    failed = stale.filter(enqueue_count__gte=max_enqueues()).update(
        status=RunStatus.FAILED,
        stage="failed",
        finished_at=timezone.now(),
        user_error=NEVER_STARTED_MESSAGE,
        developer_error=f"never claimed after {max_enqueues()} enqueues",
    )
    requeued = 0
    for run_id in stale.values_list("pk", flat=True)[:1000]:
        # Conditional, so two beat processes never both enqueue the same run.
        taken = AnalysisRun.objects.filter(
            pk=run_id, status=RunStatus.QUEUED, enqueued_at__lt=cutoff
        ).update(enqueued_at=timezone.now(), enqueue_count=F("enqueue_count") + 1)
        if taken:
            enqueue(str(run_id))
            requeued += 1
    return {"requeued": requeued, "failed": failed}


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
