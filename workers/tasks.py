"""Every Celery task of the project. Each takes ids (JSON), loads what it needs and delegates the
work to a module of `workers` (which never imports this one: tasks that enqueue others pass
them down, so there is no import cycle)."""

from __future__ import annotations

from typing import Any

from celery import shared_task

from workers import (
    analysis_task,
    exercise_models,
    housekeeping,
    inspection,
    recognition,
    reports,
    training,
)
from workers.task_guard import AnalysisTask


@shared_task(name="workers.tasks.inspect_recording", autoretry_for=(OSError,), max_retries=3)
def inspect_recording(recording_id: str) -> dict[str, Any]:
    """Parse an uploaded recording and store its frame count, joints, rate and duration."""
    return inspection.inspect_recording(recording_id)


@shared_task(name="workers.tasks.reap_stuck_runs")
def reap_stuck_runs() -> int:
    """Fail analysis runs left RUNNING past their time limit (a worker died under them)."""
    return housekeeping.reap_stuck_runs()


# Transient failures retry after 1, 2, 4, 8, 16, 30, 30, 30 s: about two minutes in all, longer
# than the lease, so even a claim whose reply was lost can be taken again by the last retries.
TRANSIENT_RETRIES = 8


def retry_delay(retries: int) -> int:
    return min(2**retries, 30)


@shared_task(
    bind=True,
    base=AnalysisTask,  # a pool process killed by the hard time limit or otherwise: task_guard
    name="workers.tasks.analyse_recording",
    max_retries=TRANSIENT_RETRIES,
    ignore_result=True,
)
def analyse_recording(self, run_id: str, token: str | None = None) -> str:
    """Analyse the recording of one run; the run ends SUCCEEDED or FAILED with a reason.

    The run's state lives in the database, so no result is kept in the broker (which may restart
    empty). A database or storage outage retries the task, resuming its own lease (`token`).
    """
    try:
        return analysis_task.analyse_run(run_id, resume_token=token)
    except analysis_task.TransientAnalysisError as failure:
        raise self.retry(
            kwargs={"run_id": run_id, "token": failure.token},
            countdown=retry_delay(self.request.retries),
            exc=failure,
        ) from failure


@shared_task(
    name="workers.tasks.recognise_exercise",  # the default (analyses) queue, like the analyses
    ignore_result=True,  # the answer is on the recording; a failure offers the choice, no retry
)
def recognise_exercise(recording_id: str) -> str:
    """Recognise the exercise of a recording uploaded without one and store the suggestion;
    nothing is analysed until someone confirms it."""
    return recognition.recognise(recording_id)


@shared_task(name="workers.tasks.requeue_lost_runs", ignore_result=True)
def requeue_lost_runs() -> dict[str, int]:
    """Enqueue again runs QUEUED for too long (their message was lost); fail hopeless ones."""
    return housekeeping.requeue_lost_runs(enqueue=enqueue_analysis)


def resume_interrupted_local_runs() -> dict[str, int] | None:
    """At a worker's start under `make run` (the folder broker: one worker, messages removed
    when taken), queue again the analyses the previous worker left unfinished; elsewhere the
    broker delivers an unacknowledged message again and nothing is done here."""
    from django.conf import settings

    if settings.CELERY_BROKER_URL != "filesystem://":
        return None
    return housekeeping.resume_interrupted_runs(enqueue=enqueue_analysis)


def enqueue_analysis(run_id: str) -> None:
    analyse_recording.delay(run_id)


def enqueue_model_build(model_id: str) -> None:
    build_exercise_model.delay(model_id)


@shared_task(name="workers.tasks.refresh_attention", ignore_result=True)
def refresh_attention() -> int:
    """Recompute every clinic's stored attention list (what changes with time alone)."""
    from webapp.dashboard.precompute import refresh_all

    return refresh_all()


@shared_task(name="workers.tasks.purge_deleted_patients", ignore_result=True)
def purge_deleted_patients() -> int:
    """Hard-delete patients soft-deleted longer ago than PATIENT_RETENTION_DAYS, with files."""
    return housekeeping.purge_deleted_patients()


@shared_task(name="workers.tasks.send_reminders", ignore_result=True)
def send_reminders() -> int:
    """E-mail today's reminders to patients behind their sessions this week (daily, by beat)."""
    from webapp.patients.reminders import send_reminders as send

    return send()


@shared_task(name="workers.tasks.build_exercise_model")
def build_exercise_model(model_id: str) -> str:
    """Fit one queued exercise-model version and make it the exercise's active version."""
    return exercise_models.build_version(model_id)


@shared_task(name="workers.tasks.rebuild_models_with_corrections")
def rebuild_models_with_corrections() -> list[str]:
    """Queue a new model version for exercises whose therapists corrected analyses since."""
    return training.rebuild_models_with_corrections(enqueue=enqueue_model_build)


@shared_task(name="workers.tasks.refit_pass_thresholds")
def refit_pass_thresholds() -> int:
    """Refit paper 001's pass/fail threshold of each exercise from therapist verdicts."""
    return training.refit_pass_thresholds()


@shared_task(name="workers.tasks.make_report", autoretry_for=(OSError,), max_retries=3)
def make_report(
    kind: str, object_id: str, name: str, since: str | None = None, until: str | None = None
) -> str:
    """Render one PDF report ("recording" or "progress") into storage under `name`."""
    return reports.make_report(kind, object_id, name, since, until)
