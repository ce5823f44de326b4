"""Celery tasks. Each takes ids (JSON), loads what it needs and delegates the work."""

from __future__ import annotations

from typing import Any

from celery import shared_task

from workers import analysis_task, exercise_models, housekeeping, inspection, training


@shared_task(name="workers.tasks.inspect_recording", autoretry_for=(OSError,), max_retries=3)
def inspect_recording(recording_id: str) -> dict[str, Any]:
    """Parse an uploaded recording and store its frame count, joints, rate and duration."""
    return inspection.inspect_recording(recording_id)


@shared_task(name="workers.tasks.reap_stuck_runs")
def reap_stuck_runs() -> int:
    """Fail analysis runs left RUNNING past their time limit (a worker died under them)."""
    return housekeeping.reap_stuck_runs()


@shared_task(name="workers.tasks.analyse_recording", autoretry_for=(OSError,), max_retries=3)
def analyse_recording(run_id: str) -> str:
    """Analyse the recording of one run; the run ends SUCCEEDED or FAILED with a reason."""
    return analysis_task.analyse_run(run_id)


@shared_task(name="workers.tasks.build_exercise_model")
def build_exercise_model(model_id: str) -> str:
    """Fit one queued exercise-model version and make it the exercise's active version."""
    return exercise_models.build_version(model_id)


@shared_task(name="workers.tasks.rebuild_models_with_corrections")
def rebuild_models_with_corrections() -> list[str]:
    """Queue a new model version for exercises whose therapists corrected analyses since."""
    return training.rebuild_models_with_corrections()


@shared_task(name="workers.tasks.refit_pass_thresholds")
def refit_pass_thresholds() -> int:
    """Refit paper 001's pass/fail threshold of each exercise from therapist verdicts."""
    return training.refit_pass_thresholds()
