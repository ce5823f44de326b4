"""The live page's status JSON: live figures, then the offline analysis's beside them."""

from __future__ import annotations

from django.test import Client

from tests.personas import make_exercise, make_recording
from webapp.live.models import LiveSession, LiveStatus
from webapp.recordings.models import AnalysisRun, RunStatus


def test_status_shows_offline_figures_once_analysed(world):
    exercise = make_exercise(world.clinic)
    recording = make_recording(world.patient, exercise)
    live = LiveSession.objects.create(
        clinic=world.clinic, patient=world.patient, exercise=exercise, recording=recording,
        status=LiveStatus.ENDED, summary={"repetitions": 1, "frames": 70},
    )  # fmt: skip
    client = Client()
    client.force_login(world.patient_user)
    body = client.get(f"/live/{live.pk}/status/").json()
    assert body["summary"]["repetitions"] == 1
    assert body["offline"]["status"] == RunStatus.QUEUED
    summary = {"repetitions": [{"start": 0, "end": 60, "score": 81.5}], "score": 81.5}
    AnalysisRun.objects.filter(recording=recording).update(
        status=RunStatus.SUCCEEDED, summary=summary, progress=100
    )
    body = client.get(f"/live/{live.pk}/status/").json()
    assert body["offline"]["repetitions"] == [{"start": 0, "end": 60, "score": 81.5}]
    assert body["offline"]["score"] == 81.5
    page = client.get(f"/live/{live.pk}/")
    assert page.status_code == 200 and live.ws_path in page.content.decode()


def test_recording_page_offers_replay_as_live(world):
    exercise = make_exercise(world.clinic)
    recording = make_recording(world.patient, exercise)
    client = Client()
    client.force_login(world.therapist)
    html = client.get(f"/recordings/{recording.pk}/").content.decode()
    assert f"/live/replay/{recording.pk}/" in html


def test_replay_of_an_exercise_without_a_model_is_refused_in_words(world):
    """Every frame of a live session is aligned with the exercise's model: without one, the
    recording page says why instead of opening a session that cannot follow."""
    exercise = make_exercise(world.clinic)
    recording = make_recording(world.patient, exercise)
    client = Client()
    client.force_login(world.therapist)
    answer = client.post(f"/live/replay/{recording.pk}/", follow=True)
    assert answer.redirect_chain[-1][0] == f"/recordings/{recording.pk}/"
    assert "model is not ready" in answer.content.decode()
    assert not LiveSession.objects.filter(replay_of=recording).exists()
