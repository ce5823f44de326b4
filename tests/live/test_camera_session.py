"""The camera page's session through the real WebSocket: a camera start, the landmarks of the phone
video of two squats as binary frames, the end; the recording saved as a MediaPipe landmark file;
an ended session refusing more frames (no second recording); the page and its start for the
patient, the patient's therapist, and nobody else."""

from __future__ import annotations

import datetime

import pytest
from asgiref.sync import async_to_sync
from django.test import Client

from analysis.bvh import read
from analysis.live.frames import encode_frames
from analysis.pipeline import build_model
from tests.analysis.fixtures.capture import make_squat_reference as squat
from tests.live.test_camera import camera_values
from tests.live.test_consumer import communicator, create_session, until
from tests.personas import PASSWORD, make_exercise
from webapp.exercises.models import ExerciseModel, ModelStatus
from webapp.live import camera, consumers, services
from webapp.live.models import LiveSession, LiveStatus
from webapp.patients.models import Prescription
from webapp.recordings.models import Recording

pytestmark = pytest.mark.django_db(transaction=True)


@pytest.fixture(scope="module")
def squat_model():
    reference = read(squat.REFERENCE)
    return build_model(reference, list(squat.KEY_POSE_FRAMES), list(squat.KEY_POSE_TYPES))


@pytest.fixture
def squat_exercise(world, squat_model, monkeypatch):
    monkeypatch.setattr("webapp.recordings.services.enqueue_analysis", lambda run_id: None)
    consumers.SESSIONS.clear()
    camera.CAMERAS.clear()
    exercise = make_exercise(world.clinic, "Back squat")
    row = ExerciseModel.objects.create_next_version(exercise, status=ModelStatus.READY)
    exercise.active_model = row
    exercise.save(update_fields=["active_model"])
    monkeypatch.setattr(services, "exercise_model", lambda _exercise: squat_model)
    return exercise


async def stream_camera(path: str, key: str) -> list[dict]:
    values, fps = camera_values()
    comm = communicator(path, key)
    assert (await comm.connect())[0]
    await comm.send_json_to({"type": "start", "source": "camera", "fps": fps})
    assert (await comm.receive_json_from(timeout=30))["camera"] is True
    events: list[dict] = []
    for first in range(0, len(values), 4):
        await comm.send_to(bytes_data=encode_frames(first, values[first : first + 4]))
        events += await comm.receive_json_from(timeout=30)
    await comm.send_json_to({"type": "end"})
    events += await until(comm, "summary")
    await comm.disconnect()
    return events


async def send_again(path: str, key: str) -> dict:
    comm = communicator(path, key)
    assert (await comm.connect())[0]
    assert (await comm.receive_json_from(timeout=30))["event"] == "summary"  # the stored one
    await comm.send_json_to({"type": "start", "source": "camera", "fps": 15})
    answer = await comm.receive_json_from(timeout=30)
    await comm.disconnect()
    return answer


def test_camera_landmarks_count_and_are_saved_as_the_recording(world, squat_exercise):
    key, created = create_session(world.therapist, world.patient, squat_exercise)
    events = async_to_sync(stream_camera)(created["ws"], key)
    assert [e for e in events if e["event"] == "error" and e["code"] != "not-in-view"] == []
    assert sum(e["event"] == "repetition" for e in events) == 2
    assert any("tutor" in e for e in events if e["event"] == "position")  # drawn beside
    summary = events[-1]
    assert summary["repetitions"] == 2
    recording = Recording.objects.get(pk=summary["recording"])
    assert recording.original_name.endswith(".json") and recording.patient == world.patient
    live = LiveSession.objects.get(pk=created["id"])
    assert live.status == LiveStatus.ENDED and live.repetitions == 2

    # an ended session stays ended: no second recording under the same name
    answer = async_to_sync(send_again)(created["ws"], key)
    assert answer["event"] == "error" and answer["code"] == "ended"
    assert Recording.objects.filter(patient=world.patient).count() == 1
    assert LiveSession.objects.get(pk=created["id"]).status == LiveStatus.ENDED


def test_the_camera_page_for_the_patient_and_their_therapist(world, squat_exercise):
    prescription = Prescription.objects.create(
        patient=world.patient, exercise=squat_exercise, start_date=datetime.date(2026, 1, 1)
    )
    url = f"/my/live/camera/{prescription.pk}/"
    patient = Client()
    assert patient.login(username="patient", password=PASSWORD)
    text = patient.get(url).content.decode()
    assert "never leave this device" in text and "data-live-count" in text
    assert 'data-live-state="waiting"' in text and "tutor" not in text.lower()
    started = patient.post(url + "start/").json()
    assert started["ws"].startswith("/ws/live/") and started["fps"] == 15
    home = patient.get("/").content.decode()
    assert url in home  # "Exercise now with your camera" beside the exercise

    therapist = Client()
    assert therapist.login(username="therapist", password=PASSWORD)
    assert therapist.get(url).status_code == 200
    assert url in therapist.get(f"/patients/{world.patient.pk}/").content.decode()
    for other in ("other-patient", "outsider"):
        client = Client()
        assert client.login(username=other, password=PASSWORD)
        assert client.get(url).status_code == 404
        assert client.post(url + "start/").status_code == 404
