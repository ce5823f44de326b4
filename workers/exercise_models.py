"""Building, storing and loading the versioned model of an exercise."""

from __future__ import annotations

import io
from typing import Any

from django.core.files.base import ContentFile
from django.db import transaction
from django.utils import timezone

from analysis import __version__ as code_version
from analysis.pipeline import FittedModel, ModelVersionError, build_model, dump_model, load_model
from webapp.exercises.models import Exercise, ExerciseModel, ModelStatus
from workers import training

# Loaded models by row id: a worker analyses many recordings of the same few exercises.
_cache: dict[str, FittedModel] = {}


def fit_for_exercise(exercise: Exercise, on_progress=None) -> FittedModel:
    return build_model(
        exercise.tutor_motion(),
        landmark_frames=list(exercise.tutor_landmark_frames),
        landmark_types=list(exercise.tutor_landmark_types),
        joints=list(exercise.involved_joints) or None,
        type_names={int(k): v for k, v in exercise.landmark_type_names.items()},
        grammar=exercise.feedback_grammar or None,
        training=training.training_recordings(exercise),
        on_progress=on_progress,
    )


def save_fitted(row: ExerciseModel, fitted: FittedModel) -> None:
    buffer = io.BytesIO()
    dump_model(fitted, buffer)
    row.artefact.save(
        f"{row.exercise_id}-v{row.version}.model", ContentFile(buffer.getvalue()), save=False
    )
    row.training_report = fitted.report
    row.status = ModelStatus.READY
    row.progress = 100
    row.code_version = code_version
    row.finished_at = timezone.now()
    row.save()


def build_now(exercise: Exercise, stale: Any = None) -> tuple[ExerciseModel, FittedModel]:
    """Build and activate a new version in this process (cold start from the tutor), unless
    another process already activated one other than the ``stale`` row's id."""
    with transaction.atomic():
        locked = Exercise.objects.select_for_update().get(pk=exercise.pk)
        if locked.active_model_id is not None and locked.active_model_id != stale:
            row = ExerciseModel.objects.get(pk=locked.active_model_id)
            return row, load_row(row)
        row = ExerciseModel.objects.create_next_version(locked, status=ModelStatus.RUNNING)
        fitted = fit_for_exercise(locked)
        save_fitted(row, fitted)
        Exercise.objects.filter(pk=locked.pk).update(active_model=row)
    _cache[str(row.pk)] = fitted
    return row, fitted


def load_row(row: ExerciseModel) -> FittedModel:
    key = str(row.pk)
    if key not in _cache:
        with row.artefact.open("rb") as handle:
            _cache[key] = load_model(handle.read())
    return _cache[key]


def active_model(exercise: Exercise) -> tuple[ExerciseModel, Any]:
    exercise.refresh_from_db(fields=["active_model"])
    if exercise.active_model_id is None:
        return build_now(exercise)
    row = ExerciseModel.objects.get(pk=exercise.active_model_id)
    try:
        return row, load_row(row)
    except ModelVersionError:
        # written by an earlier version of the analysis code: fit it again from the same tutor
        return build_now(exercise, stale=row.pk)


def build_version(model_id: str) -> str:
    """Claim a QUEUED model row, fit it with progress, activate it; FAILED with a reason."""
    claimed = ExerciseModel.objects.filter(pk=model_id, status=ModelStatus.QUEUED).update(
        status=ModelStatus.RUNNING, progress=1
    )
    if claimed != 1:
        return "skipped"
    row = ExerciseModel.objects.select_related("exercise").get(pk=model_id)

    def on_progress(stage: str, fraction: float) -> None:
        ExerciseModel.objects.filter(pk=model_id).update(progress=max(1, int(99 * fraction)))

    try:
        fitted = fit_for_exercise(row.exercise, on_progress=on_progress)
    except Exception as error:  # the row must end with a reason whatever went wrong
        ExerciseModel.objects.filter(pk=model_id).update(
            status=ModelStatus.FAILED, error=str(error)[:2000], finished_at=timezone.now()
        )
        return "failed"
    save_fitted(row, fitted)
    Exercise.objects.filter(pk=row.exercise_id).update(active_model=row)
    training.mark_used(row.exercise, row)
    return "ready"
