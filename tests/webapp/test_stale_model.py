"""An exercise model written by an earlier version of the analysis code is fitted again from the
same tutor the first time a worker's analysis needs it (instead of failing every analysis)."""

from __future__ import annotations

import io

import pytest
from django.core.files.base import ContentFile

from analysis.pipeline import dump_model
from analysis.pipeline.model import FORMAT_VERSION
from tests.personas import make_exercise
from webapp.exercises.models import Exercise
from workers import exercise_models


@pytest.mark.slow
def test_a_stale_model_file_is_rebuilt_once(world):
    exercise = make_exercise(world.clinic)
    row, fitted = exercise_models.build_active(exercise)
    buffer = io.BytesIO()
    dump_model(fitted, buffer)
    old = buffer.getvalue().replace(f"\n{FORMAT_VERSION}\n".encode(), b"\n1\n", 1)
    row.artefact.save("old-model.bin", ContentFile(old))
    exercise_models._cache.clear()

    new_row, new_model = exercise_models.load_or_build(exercise)
    assert new_row.version == row.version + 1
    assert Exercise.objects.get(pk=exercise.pk).active_model_id == new_row.pk
    assert new_model.components.papers.gesture_scale > 1e-3
    again, _ = exercise_models.load_or_build(exercise)
    assert again.pk == new_row.pk
