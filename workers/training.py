"""Therapist corrections as training data (Celery beat).

`rebuild_models_with_corrections`: an exercise with corrections not yet used by a model gets a new
model version fitted on its tutor plus the corrected recordings (landmarks as corrected, label from
the corrected levels); the corrections then point at the version that used them.
`refit_pass_thresholds`: paper 001's pass/fail score threshold (Bayes boundary between the score
distributions of passed and failed repetitions, eqs 13-15) refitted from therapist verdicts.
"""

from __future__ import annotations

import statistics
from collections.abc import Callable
from typing import Any

from django.db import transaction
from django.db.models import Q
from django.utils import timezone

from analysis.bvh import read
from analysis.online import BayesThreshold
from analysis.pipeline import TrainingRecording
from webapp.exercises.models import Exercise, ExerciseModel, ModelStatus
from webapp.recordings.models import (
    AnalysisRun,
    AssessmentCorrection,
    LandmarkCorrection,
    RepetitionLabel,
)
from webapp.recordings.storage import read_verified

MIN_PER_CLASS = 2


def corrected_runs(exercise: Exercise):
    return (
        AnalysisRun.objects.filter(
            Q(landmark_fixes__isnull=False) | Q(assessment_fixes__isnull=False),
            recording__exercise=exercise,
        )
        .distinct()
        .select_related("recording")
    )


def run_label(run: AnalysisRun) -> str:
    """The worst corrected level, else the median of the analysis' worst level per key pose."""
    corrected = list(run.assessment_fixes.values_list("level", flat=True))
    if corrected:
        return str(max(1, min(4, max(corrected))))
    assessment = run.result.assessment if run.result else ()
    worst = [max(a.levels.values()) for a in assessment if a.levels]
    return str(max(1, min(4, round(statistics.median(worst))))) if worst else "correct"


def training_recording(run: AnalysisRun) -> TrainingRecording:
    fix = run.landmark_fixes.order_by("-created_at").first()
    if fix is not None:
        frames, types = fix.frames, fix.types
    else:
        marks = run.result.landmarks if run.result else ()
        frames, types = [m.frame for m in marks], [m.type for m in marks]
    motion = read(read_verified(run.recording))
    return TrainingRecording(motion, tuple(frames), tuple(types), run_label(run))


def training_recordings(exercise: Exercise) -> list[TrainingRecording]:
    return [training_recording(run) for run in corrected_runs(exercise)]


def pending_exercises() -> list[Exercise]:
    """Exercises with corrections no model has used yet, and no build already under way."""
    ids = set()
    for model in (LandmarkCorrection, AssessmentCorrection):
        unused = model.objects.filter(used_in_model__isnull=True)
        ids |= set(unused.values_list("run__recording__exercise_id", flat=True))
    building = ExerciseModel.objects.filter(status__in=[ModelStatus.QUEUED, ModelStatus.RUNNING])
    ids -= set(building.values_list("exercise_id", flat=True))
    return list(Exercise.objects.filter(pk__in=ids - {None}, archived_at__isnull=True))


def mark_used(exercise: Exercise, model: ExerciseModel) -> None:
    runs = AnalysisRun.objects.filter(recording__exercise=exercise)
    LandmarkCorrection.objects.filter(run__in=runs, used_in_model__isnull=True).update(
        used_in_model=model
    )
    AssessmentCorrection.objects.filter(run__in=runs, used_in_model__isnull=True).update(
        used_in_model=model
    )


def rebuild_models_with_corrections(enqueue: Callable[[str], object]) -> list[str]:
    """Queue a new model version for every exercise with unused corrections; returns row ids.

    `enqueue(model_id)` hands each new row to the broker after the commit (the task module
    passes the build task's).
    """
    queued = []
    for exercise in pending_exercises():
        with transaction.atomic():
            row_id = str(ExerciseModel.objects.create_next_version(exercise).pk)
            transaction.on_commit(lambda row_id=row_id: enqueue(row_id))
        queued.append(row_id)
    return queued


def threshold_data(exercise: Exercise) -> tuple[list[float], list[bool]]:
    scores, failed = [], []
    labels = RepetitionLabel.objects.filter(run__recording__exercise=exercise).select_related("run")
    for label in labels:
        repetitions = label.run.result.repetitions if label.run.result else ()
        if label.index < len(repetitions):
            scores.append(repetitions[label.index].score)
            failed.append(not label.passed)
    return scores, failed


def refit_threshold(exercise: Exercise) -> dict[str, Any] | None:
    scores, failed = threshold_data(exercise)
    n_failed = sum(failed)
    if min(n_failed, len(failed) - n_failed) < MIN_PER_CLASS:
        return None
    fitted = BayesThreshold().fit(scores, failed)
    report = {
        "n_passed": len(failed) - n_failed,
        "n_failed": n_failed,
        "mean_passed": float(fitted.means_[0]),
        "mean_failed": float(fitted.means_[1]),
        "std_passed": float(fitted.stds_[0]),
        "std_failed": float(fitted.stds_[1]),
        "fitted_at": timezone.now().isoformat(),
    }
    Exercise.objects.filter(pk=exercise.pk).update(
        pass_threshold=float(fitted.threshold_), threshold_report=report
    )
    return report


def refit_pass_thresholds() -> int:
    """Refit the threshold of every exercise with labelled repetitions; returns how many."""
    labelled = Exercise.objects.filter(recordings__runs__repetition_labels__isnull=False).distinct()
    return sum(refit_threshold(exercise) is not None for exercise in labelled)
