import gzip
from pathlib import Path

import pytest

from analysis.bvh import read
from analysis.pipeline import FittedModel, build_model
from tests.personas import FIXTURES, World, fixture_landmarks, make_world
from tests.webapp.conftest import (  # noqa: F401 (fixtures shared with the web tests)
    _eager_tasks,
    _fast_password_hashing,
    _isolated_media,
)

TUTOR = "sessions/m07_s01_correct.bvh.gz"


@pytest.fixture(autouse=True)
def _fresh_channel_layer():
    """A new channel layer per test: each test drives the consumer from its own event loop, and
    the Redis layer (used when REDIS_URL is set) binds its locks to the loop that first used it;
    a server process has one loop for its whole life."""
    from channels.layers import channel_layers

    channel_layers.backends.clear()
    yield
    channel_layers.backends.clear()


@pytest.fixture(scope="session")
def live_model() -> FittedModel:
    """The shoulder-abduction model built once from its UI-PRMD tutor (a few seconds)."""
    frames, types = fixture_landmarks(TUTOR)
    return build_model(read(FIXTURES / TUTOR), frames, types)


@pytest.fixture
def short_recording() -> bytes:
    """About three repetitions of another subject (250 frames at 30 fps), as BVH text."""
    text = gzip.decompress((FIXTURES / "sessions/m07_s02_correct.bvh.gz").read_bytes()).decode()
    header, motion = text.split("MOTION")
    lines = motion.strip().splitlines()
    return (header + "MOTION\nFrames: 250\n" + "\n".join(lines[1:252]) + "\n").encode()


@pytest.fixture
def world(db) -> World:
    return make_world()


@pytest.fixture
def exercise_with_model(world, live_model, monkeypatch):
    """An exercise of the world's clinic whose active model is `live_model` (no build)."""
    from tests.personas import make_exercise
    from webapp.exercises.models import ExerciseModel, ModelStatus
    from webapp.live import services

    exercise = make_exercise(world.clinic, "Shoulder abduction", TUTOR)
    # a stored version marks the exercise as followable; its loading is `live_model`
    row = ExerciseModel.objects.create_next_version(exercise, status=ModelStatus.READY)
    exercise.active_model = row
    exercise.save(update_fields=["active_model"])
    monkeypatch.setattr(services, "exercise_model", lambda _exercise: live_model)
    return exercise


def path_of(relative: str) -> Path:
    return FIXTURES / relative
