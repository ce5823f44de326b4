"""Building, storing and loading the versioned model of an exercise.

Loading and building are separate on purpose. `load_active` only reads the exercise's active
stored version (once per process: `_cache`, by model row id) and raises `NoUsableModelError` when
there is none it can use; the web server, live sessions included, only ever loads. Building
(fitting, storing and activating a version) is an explicit call: `build_active` in this process,
`build_version` for a version queued by the web app (`webapp.exercises.services`), and
`load_or_build` where a worker may build the first version of an exercise itself.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from typing import Any

from django.core.files.base import ContentFile
from django.db import transaction
from django.utils import timezone

from analysis import __version__ as code_version
from analysis.pipeline import FittedModel, ModelVersionError, build_model, dump_model, load_model
from webapp.exercises.annotate_data import rig_grammar
from webapp.exercises.models import Exercise, ExerciseModel, ModelStatus
from workers import training

# Loaded models by row id: a worker (or a server process) uses the same few exercises over and
# over, and a stored version never changes. Bounded, so a process serving many exercises keeps
# only the most recently stored ones (a model is tens of MB).
_cache: dict[str, FittedModel] = {}
CACHE_SIZE = 16


class NoUsableModelError(ValueError):
    """The exercise has no active model version this code can read.

    ``stale``: the id of the active version that is unreadable (written by an earlier version of
    the analysis code), None when the exercise has no active version at all.
    """

    def __init__(self, exercise: Exercise, stale: Any = None) -> None:
        why = "was made by an earlier version of the software" if stale else "is not built yet"
        super().__init__(f"The model of the exercise {exercise.name!r} {why}.")
        self.stale = stale


def fit_for_exercise(
    exercise: Exercise, on_progress: Callable[[str, float], None] | None = None
) -> FittedModel:
    # read first: a reference video's first reading also fills in suggested key poses
    tutor = exercise.tutor_motion()
    return build_model(
        tutor,
        landmark_frames=list(exercise.tutor_landmark_frames),
        landmark_types=list(exercise.tutor_landmark_types),
        joints=list(exercise.involved_joints) or None,
        type_names={int(k): v for k, v in exercise.landmark_type_names.items()},
        grammar=rig_grammar(exercise.feedback_grammar, tutor.skeleton) or None,
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


def remember(row_id: Any, fitted: FittedModel) -> FittedModel:
    if len(_cache) >= CACHE_SIZE:
        _cache.pop(next(iter(_cache)))  # the oldest loaded
    _cache[str(row_id)] = fitted
    return fitted


def load_row(row: ExerciseModel) -> FittedModel:
    """The stored version, read once per process; ModelVersionError for an older format."""
    cached = _cache.get(str(row.pk))
    if cached is not None:
        return cached
    with row.artefact.open("rb") as handle:
        return remember(row.pk, load_model(handle.read()))


def load_active(exercise: Exercise) -> tuple[ExerciseModel, FittedModel]:
    """The exercise's active version and its model. Never fits nor writes anything: raises
    NoUsableModelError when the exercise has no active version or only one of an older format."""
    exercise.refresh_from_db(fields=["active_model"])
    if exercise.active_model_id is None:
        raise NoUsableModelError(exercise)
    row = ExerciseModel.objects.get(pk=exercise.active_model_id)
    try:
        return row, load_row(row)
    except ModelVersionError as error:
        raise NoUsableModelError(exercise, stale=row.pk) from error


def build_active(exercise: Exercise, replacing: Any = None) -> tuple[ExerciseModel, FittedModel]:
    """Fit, store and activate a new version in this process (from the tutor and any labelled
    training recordings), unless another process meanwhile activated a version other than the
    unusable ``replacing`` one: that version is then loaded instead of fitting a second."""
    with transaction.atomic():
        locked = Exercise.objects.select_for_update().get(pk=exercise.pk)
        if locked.active_model_id is not None and locked.active_model_id != replacing:
            row = ExerciseModel.objects.get(pk=locked.active_model_id)
            return row, load_row(row)
        row = ExerciseModel.objects.create_next_version(locked, status=ModelStatus.RUNNING)
        fitted = fit_for_exercise(locked)
        save_fitted(row, fitted)
        Exercise.objects.filter(pk=locked.pk).update(active_model=row)
    return row, remember(row.pk, fitted)


def load_or_build(exercise: Exercise) -> tuple[ExerciseModel, FittedModel]:
    """For workers only: the active version, or a new one built now when the exercise has none
    usable (its first analysis, or a version an earlier code wrote). The web never calls this."""
    try:
        return load_active(exercise)
    except NoUsableModelError as missing:
        return build_active(exercise, replacing=missing.stale)


def build_version(model_id: str) -> str:
    """Claim a QUEUED model row, fit it with progress, activate it; FAILED with a reason."""
    claimed = ExerciseModel.objects.filter(pk=model_id, status=ModelStatus.QUEUED).update(
        status=ModelStatus.RUNNING, progress=1
    )
    if claimed != 1:
        return "skipped"
    row = ExerciseModel.objects.select_related("exercise").get(pk=model_id)

    # a reference video's reading shows as the first 80 % (Exercise.reading), fitting after it
    start = 80 if row.exercise.tutor_is_video else 1

    def on_progress(stage: str, fraction: float) -> None:
        progress = start + int((99 - start) * fraction)
        ExerciseModel.objects.filter(pk=model_id).update(progress=progress)

    try:
        fitted = fit_for_exercise(row.exercise, on_progress=on_progress)
    except Exception as error:  # the row must end with a reason whatever went wrong
        ExerciseModel.objects.filter(pk=model_id).update(
            status=ModelStatus.FAILED, error=str(error)[:2000], finished_at=timezone.now()
        )
        return "failed"
    save_fitted(row, fitted)
    # A replaced reference whose key poses await the therapist's confirmation is not put in use.
    Exercise.objects.filter(pk=row.exercise_id, key_poses_to_confirm=False).update(active_model=row)
    training.mark_used(row.exercise, row)
    return "ready"
