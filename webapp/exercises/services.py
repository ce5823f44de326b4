"""Enqueueing model builds after the commit (the web app's door to the queue for exercises)."""

from __future__ import annotations

from django.db import transaction
from django.db.models import Max

from webapp.exercises.models import Exercise, ExerciseModel


def start_model_build(exercise: Exercise) -> ExerciseModel:
    from workers.tasks import build_exercise_model

    with transaction.atomic():
        locked = Exercise.objects.select_for_update().get(pk=exercise.pk)
        latest = locked.models.aggregate(v=Max("version"))["v"] or 0
        row = ExerciseModel.objects.create(exercise=locked, version=latest + 1)
        row_id = str(row.pk)
        transaction.on_commit(lambda: build_exercise_model.delay(row_id))
    return row
