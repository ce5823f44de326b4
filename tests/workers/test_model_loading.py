"""Loading an exercise model only loads; building one is an explicit call (issue 22, item 4).

`load_active` never fits nor stores a version (the web server and its live sessions only load);
`build_active` fits, stores and activates one; a worker builds the first version itself through
`load_or_build`; a live session of an exercise without a usable model is refused with words a
therapist can act on.
"""

from __future__ import annotations

import io

import pytest
from asgiref.sync import async_to_sync
from channels.testing import WebsocketCommunicator
from django.core.files.base import ContentFile
from rest_framework.test import APIClient

from analysis.bvh import read
from analysis.live import header_text
from analysis.pipeline import dump_model
from analysis.pipeline.model import FORMAT_VERSION
from tests.personas import FIXTURES, make_exercise, make_world
from webapp.accounts.tokens import issue_token
from webapp.asgi import application
from webapp.exercises.models import Exercise, ExerciseModel
from webapp.live import consumers, services
from workers import exercise_models

TUTOR = "reps/m01_s01_e01.bvh.gz"


@pytest.fixture(autouse=True)
def _isolated(settings, tmp_path):
    settings.MEDIA_ROOT = tmp_path / "media"
    settings.PASSWORD_HASHERS = ["django.contrib.auth.hashers.MD5PasswordHasher"]
    exercise_models._cache.clear()
    services._REHEARSED.clear()
    yield
    exercise_models._cache.clear()
    services._REHEARSED.clear()


@pytest.fixture
def exercise(db) -> Exercise:
    return make_exercise(make_world().clinic)


def make_stale(row: ExerciseModel) -> None:
    """Rewrite the stored version as an earlier code would have written it (older format)."""
    buffer = io.BytesIO()
    dump_model(exercise_models.load_row(row), buffer)
    old = buffer.getvalue().replace(f"\n{FORMAT_VERSION}\n".encode(), b"\n1\n", 1)
    row.artefact.save("old-model.bin", ContentFile(old))
    exercise_models._cache.clear()


def test_loading_an_exercise_without_a_model_fits_and_stores_nothing(exercise, monkeypatch):
    monkeypatch.setattr(exercise_models, "build_model", pytest.fail)  # any fit fails the test
    with pytest.raises(exercise_models.NoUsableModelError) as refused:
        exercise_models.load_active(exercise)
    assert refused.value.stale is None
    assert ExerciseModel.objects.count() == 0
    assert Exercise.objects.get(pk=exercise.pk).active_model_id is None


def test_the_build_service_fits_stores_and_activates_a_version(exercise):
    row, fitted = exercise_models.build_active(exercise)
    assert ExerciseModel.objects.filter(exercise=exercise).count() == 1
    assert Exercise.objects.get(pk=exercise.pk).active_model_id == row.pk
    exercise_models._cache.clear()  # what another process reads back from storage
    loaded_row, loaded = exercise_models.load_active(exercise)
    assert loaded_row.pk == row.pk
    assert loaded.tutor.frames.shape == fitted.tutor.frames.shape


def test_a_stored_model_is_loaded_once_per_process_and_never_refitted(exercise, monkeypatch):
    exercise_models.build_active(exercise)
    exercise_models._cache.clear()
    reads = []
    real_load = exercise_models.load_model
    monkeypatch.setattr(
        exercise_models, "load_model", lambda data: reads.append(1) or real_load(data)
    )
    monkeypatch.setattr(exercise_models, "build_model", pytest.fail)
    first = exercise_models.load_active(exercise)[1]
    second = exercise_models.load_active(exercise)[1]
    assert first is second and len(reads) == 1
    assert ExerciseModel.objects.count() == 1


def test_loading_a_model_of_an_older_format_refuses_without_building(exercise):
    row, _ = exercise_models.build_active(exercise)
    make_stale(row)
    with pytest.raises(exercise_models.NoUsableModelError) as refused:
        exercise_models.load_active(exercise)
    assert refused.value.stale == row.pk
    assert ExerciseModel.objects.count() == 1


def test_a_worker_builds_the_first_version_then_loads_it(exercise):
    row, _ = exercise_models.load_or_build(exercise)
    again, _ = exercise_models.load_or_build(exercise)
    assert again.pk == row.pk
    assert ExerciseModel.objects.count() == 1


def test_the_live_service_refuses_an_exercise_without_a_model_in_plain_words(exercise):
    with pytest.raises(services.ModelNotReadyError, match="Build model") as refused:
        services.exercise_model(exercise)
    assert "exercise's page" in str(refused.value)
    assert ExerciseModel.objects.count() == 0


def test_the_live_service_asks_to_rebuild_a_model_of_an_older_format(exercise):
    row, _ = exercise_models.build_active(exercise)
    make_stale(row)
    with pytest.raises(services.ModelNotReadyError, match="earlier version of the software"):
        services.exercise_model(exercise)
    assert ExerciseModel.objects.count() == 1
    assert Exercise.objects.get(pk=exercise.pk).active_model_id == row.pk


def test_the_live_service_loads_and_rehearses_a_model_once(exercise, monkeypatch):
    exercise_models.build_active(exercise)
    rehearsed = []
    monkeypatch.setattr(services, "rehearse", rehearsed.append)
    first = services.exercise_model(exercise)
    assert services.exercise_model(exercise) is first
    assert rehearsed == [first]
    assert ExerciseModel.objects.count() == 1


async def first_answer(path: str, key: str) -> dict:
    comm = WebsocketCommunicator(
        application, path, headers=[(b"authorization", f"Token {key}".encode())]
    )
    connected, _ = await comm.connect()
    assert connected
    header = header_text(read(FIXTURES / "sessions/m07_s02_correct.bvh.gz"))
    await comm.send_json_to({"type": "start", "header": header})
    answer = await comm.receive_json_from(timeout=30)
    await comm.disconnect()
    return answer


@pytest.mark.django_db(transaction=True)
def test_a_live_session_without_a_model_is_refused_with_the_reason():
    world = make_world()
    exercise = make_exercise(world.clinic, "Shoulder abduction", "sessions/m07_s01_correct.bvh.gz")
    _, key = issue_token(world.therapist, "capture")
    client = APIClient()
    client.credentials(HTTP_AUTHORIZATION=f"Token {key}")
    refused = client.post(
        "/api/v1/live-sessions/", {"patient": str(world.patient.pk), "exercise": str(exercise.pk)}
    )
    assert refused.status_code == 409 and refused.json()["detail"] == services.NOT_BUILT
    # a session opened before its exercise lost its model (one made by an earlier version)
    live = services.create_session(patient=world.patient, exercise=exercise, user=world.therapist)
    created = {"id": live.pk, "ws": live.ws_path}
    consumers.SESSIONS.clear()
    answer = async_to_sync(first_answer)(created["ws"], key)
    assert answer["event"] == "error"
    assert answer["message"] == services.NOT_BUILT
    assert ExerciseModel.objects.count() == 0
    assert str(created["id"]) not in consumers.SESSIONS
