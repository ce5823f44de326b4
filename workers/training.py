"""Therapist corrections as training data (Celery beat).

`rebuild_models_with_corrections`: an exercise with corrections not yet used by a model gets a new
model version fitted on its tutor plus the corrected recordings (landmarks as corrected, label from
the corrected levels); the corrections then point at the version that used them.
`refit_pass_thresholds`: the pass threshold is the same stated number on every exercise
(`PASS_SCORE`, 70: issue 17's one scale), so therapist verdicts never move it. They train the
model instead: a run with verdicts is a labelled recording of the next model version (which maps
its own labelled boundary onto 70), and a verdict newer than the exercise's newest model queues a
rebuild. The refit reports where the verdicts would put the boundary on today's scores (paper
001's Bayes boundary, eqs 13-15) and how often a score of 70 or more agrees with them.
"""

from __future__ import annotations

import statistics
from collections.abc import Callable
from typing import Any

from django.db import transaction
from django.db.models import Max, Q
from django.utils import timezone

from analysis.assessment.scoring import PASS_SCORE
from analysis.landmarks import KeyPoses
from analysis.online import BayesThreshold
from analysis.pipeline import TrainingRecording
from analysis.sources import read_recording
from webapp.exercises.models import Exercise, ExerciseModel, ModelStatus
from webapp.recordings.models import (
    AnalysisRun,
    AssessmentCorrection,
    LandmarkCorrection,
    RepetitionLabel,
)
from webapp.recordings.storage import read_verified

MIN_PER_CLASS = 2


def of_exercise(exercise: Exercise) -> Q:
    """Runs of the exercise's recordings analysed with its model: a recording moved to another
    exercise keeps its earlier runs, whose corrections speak of the other exercise's key poses;
    a deleted recording teaches nothing."""
    return Q(recording__exercise=exercise, recording__deleted_at__isnull=True) & (
        Q(model__isnull=True) | Q(model__exercise=exercise)
    )


def corrected_runs(exercise: Exercise):
    return (
        AnalysisRun.objects.filter(
            Q(landmark_fixes__isnull=False)
            | Q(assessment_fixes__isnull=False)
            | Q(repetition_labels__isnull=False),
            of_exercise(exercise),
        )
        .distinct()
        .select_related("recording")
    )


def run_label(run: AnalysisRun) -> str:
    """The worst corrected level; else the therapist's verdicts ("correct" when at least half of
    the judged repetitions passed); else the median of the analysis' worst level per key pose."""
    corrected = list(run.assessment_fixes.values_list("level", flat=True))
    if corrected:
        return str(max(1, min(4, max(corrected))))
    verdicts = list(run.repetition_labels.values_list("passed", flat=True))
    if verdicts:
        return "correct" if 2 * sum(verdicts) >= len(verdicts) else "incorrect"
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
    motion = read_recording(run.recording.file.name, read_verified(run.recording)).motion
    return TrainingRecording(motion, KeyPoses.of(frames, types), run_label(run))


def training_recordings(exercise: Exercise) -> list[TrainingRecording]:
    return [training_recording(run) for run in corrected_runs(exercise)]


def pending_exercises() -> list[Exercise]:
    """Exercises with corrections no model has used yet, and no build already under way."""
    ids = set()
    for model in (LandmarkCorrection, AssessmentCorrection):
        unused = model.objects.filter(used_in_model__isnull=True)
        ids |= set(unused.values_list("run__recording__exercise_id", flat=True))
    ids |= exercises_with_new_verdicts()
    building = ExerciseModel.objects.filter(status__in=[ModelStatus.QUEUED, ModelStatus.RUNNING])
    ids -= set(building.values_list("exercise_id", flat=True))
    return list(Exercise.objects.filter(pk__in=ids - {None}, archived_at__isnull=True))


def exercises_with_new_verdicts() -> set[Any]:
    """Exercises with a pass/fail verdict newer than their newest model version."""
    newest_label = dict(
        RepetitionLabel.objects.values_list("run__recording__exercise_id")
        .annotate(at=Max("created_at"))
        .values_list("run__recording__exercise_id", "at")
    )
    newest_model = dict(
        ExerciseModel.objects.filter(exercise_id__in=list(newest_label))
        .values_list("exercise_id")
        .annotate(at=Max("created_at"))
        .values_list("exercise_id", "at")
    )
    return {e for e, at in newest_label.items() if e not in newest_model or at > newest_model[e]}


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
    labels = RepetitionLabel.objects.filter(
        run__in=AnalysisRun.objects.filter(of_exercise(exercise))
    ).select_related("run")
    for label in labels:
        repetitions = label.run.result.repetitions if label.run.result else ()
        if label.index < len(repetitions):
            scores.append(repetitions[label.index].score)
            failed.append(not label.passed)
    return scores, failed


def refit_threshold(exercise: Exercise) -> dict[str, Any] | None:
    """Report what the verdicts say about the one threshold; it stays `PASS_SCORE`."""
    scores, failed = threshold_data(exercise)
    n_failed = sum(failed)
    if min(n_failed, len(failed) - n_failed) < MIN_PER_CLASS:
        return None
    fitted = BayesThreshold().fit(scores, failed)
    agree = sum((s >= PASS_SCORE) != f for s, f in zip(scores, failed, strict=True))
    report = {
        "n_passed": len(failed) - n_failed,
        "n_failed": n_failed,
        "mean_passed": float(fitted.means_[0]),
        "mean_failed": float(fitted.means_[1]),
        "std_passed": float(fitted.stds_[0]),
        "std_failed": float(fitted.stds_[1]),
        "verdict_boundary": float(fitted.threshold_),
        "agreement": agree / len(failed),
        "fitted_at": timezone.now().isoformat(),
    }
    Exercise.objects.filter(pk=exercise.pk).update(
        pass_threshold=PASS_SCORE, threshold_report=report
    )
    return report


def refit_pass_thresholds() -> int:
    """Report the verdicts of every exercise with labelled repetitions (the threshold stays
    `PASS_SCORE`); returns how many."""
    labelled = Exercise.objects.filter(recordings__runs__repetition_labels__isnull=False).distinct()
    return sum(refit_threshold(exercise) is not None for exercise in labelled)
