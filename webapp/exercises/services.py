"""Enqueueing model builds after the commit (the web app's door to the queue for exercises)."""

from __future__ import annotations

from django.db import transaction

from webapp.exercises.models import Exercise, ExerciseModel
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
