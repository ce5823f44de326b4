"""Enqueueing model builds after the commit (the web app's door to the queue for exercises)."""

from __future__ import annotations

from django.core.files.base import ContentFile
from django.db import transaction

from webapp.exercises.models import Exercise, ExerciseModel
from webapp.recordings.uploads import ParsedUpload
from workers.tasks import build_exercise_model


def start_model_build(exercise: Exercise) -> ExerciseModel:
    """A new QUEUED model version, built by a worker once the transaction commits."""
    with transaction.atomic():
        row = ExerciseModel.objects.create_next_version(exercise)
        row_id = str(row.pk)
        transaction.on_commit(lambda: build_exercise_model.delay(row_id))
    return row


def build_model_now(exercise: Exercise) -> ExerciseModel:
    """The exercise's active model version; the first one is built in this process (no queue)."""
    exercise.refresh_from_db(fields=["active_model"])
    if exercise.active_model is None:
        row = ExerciseModel.objects.create_next_version(exercise)
        build_exercise_model.apply(args=[str(row.pk)])
        exercise.refresh_from_db(fields=["active_model"])
        if exercise.active_model is None:
            row.refresh_from_db()
            raise RuntimeError(f"building {exercise} version {row.version} failed: {row.error}")
    return exercise.active_model


def save_reference(exercise: Exercise, parsed: ParsedUpload, name: str) -> None:
    """Store a reference file under ``name`` with its real ending (so it is read back the way it
    was checked: `Exercise.tutor_motion`), on the row (not saved)."""
    exercise.tutor_checksum = parsed.checksum
    exercise.tutor_file.save(f"{name}{parsed.suffix}", ContentFile(parsed.content), save=False)


def create_exercise(exercise: Exercise, parsed: ParsedUpload) -> None:
    """Save a new exercise with its reference. A video's frames are the worker's to read (about
    30 ms a frame): a model build starts at once and reads it, showing its progress."""
    with transaction.atomic():
        save_reference(exercise, parsed, str(exercise.pk))
        exercise.save()
        if exercise.tutor_is_video:
            start_model_build(exercise)


def replace_reference(exercise: Exercise, parsed: ParsedUpload) -> ExerciseModel | None:
    """Store a new reference recording with key poses suggested from it, to be confirmed.

    The earlier file and model versions stay, and the active version stays in use: no version is
    built from the new reference until the therapist confirms its key poses
    (`confirm_key_poses`), never from frames marked on the old recording. A video is read by a
    model build first (its key poses are suggested then: `Exercise.read_video_tutor`); that
    version is not made active (workers.exercise_models.build_version)."""
    with transaction.atomic():
        save_reference(exercise, parsed, f"{exercise.pk}-{parsed.checksum[:12]}")
        exercise.key_poses_to_confirm = True
        if parsed.motion is not None:
            exercise.take_key_poses(parsed.motion)
        exercise.save()
        return start_model_build(exercise) if exercise.tutor_is_video else None


def confirm_key_poses(exercise: Exercise) -> ExerciseModel | None:
    """The therapist saved the key poses of a replaced reference: build the version that
    replaces the one in use (None when nothing was waiting for a confirmation)."""
    if not exercise.key_poses_to_confirm:
        return None
    with transaction.atomic():
        Exercise.objects.filter(pk=exercise.pk).update(key_poses_to_confirm=False)
        exercise.key_poses_to_confirm = False
        return start_model_build(exercise)
