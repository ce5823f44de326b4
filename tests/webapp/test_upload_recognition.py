"""An upload without exercise answers at once; a worker recognises the exercise among the
patient's prescribed ones and the recording page asks to confirm it; confirming analyses."""

from __future__ import annotations

import datetime
import time

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.urls import reverse
from rest_framework.test import APIClient

from tests.personas import fixture_bytes, make_exercise
from webapp.patients.models import Prescription
from webapp.recordings.models import AnalysisRun, Recording
from workers.recognition import recognise

SQUAT = "reps/m01_s01_e02.bvh.gz"
ABDUCTION = "reps/m07_s01_e02.bvh.gz"


@pytest.fixture
def exercises(world):
    squat = make_exercise(world.clinic, source="reps/m01_s01_e01.bvh.gz")
    abduction = make_exercise(
        world.clinic, name="Shoulder abduction", source="reps/m07_s01_e01.bvh.gz"
    )
    return squat, abduction


@pytest.fixture
def queued(monkeypatch):
    """What the web app hands to the broker, instead of a broker."""
    handed: dict[str, list[str]] = {"recognise": [], "analyse": []}
    monkeypatch.setattr("workers.tasks.recognise_exercise.delay", handed["recognise"].append)
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", handed["analyse"].append)
    return handed


@pytest.fixture(autouse=True)
def warm_reader():
    """The BVH reader's compiled code loaded, as the upload page does while a person chooses a
    file (`webapp/recordings/warmup.py`): a once-per-process cost of 1.5-3 s that is not what
    the bounds below are about (recognition, 44-47 s when it ran inside the request)."""
    from analysis.bvh import read
    from analysis.kinematics import positions

    positions(read(fixture_bytes(SQUAT)))


def prescribe(patient, exercise, **dates):
    start = datetime.date.today() - datetime.timedelta(days=30)
    return Prescription.objects.create(
        patient=patient, exercise=exercise, start_date=start, **dates
    )


def upload_without_exercise(client, capture, source: str = SQUAT):
    """The patient's upload, its after-commit work included; returns the answer and its time."""
    data = {"exercise": "", "file": SimpleUploadedFile("t.bvh.gz", fixture_bytes(source))}
    url = reverse("recordings:upload")
    client.get(url)  # the form a person fills in first (the site's code loaded, once a process)
    with capture(execute=True):
        start = time.perf_counter()
        response = client.post(url, data)
        seconds = time.perf_counter() - start
    return response, seconds


def test_upload_without_exercise_answers_at_once_and_queues_recognition(
    client, world, exercises, queued, django_capture_on_commit_callbacks
):
    client.force_login(world.patient_user)
    response, seconds = upload_without_exercise(client, django_capture_on_commit_callbacks)
    recording = Recording.objects.get()
    assert response.status_code == 302
    assert response["Location"] == reverse("recordings:detail", kwargs={"pk": recording.pk})
    assert seconds < 1.0, f"the upload took {seconds:.2f} s"
    assert queued["recognise"] == [str(recording.pk)] and queued["analyse"] == []
    assert recording.recognition == "queued" and recording.suggested_exercise is None
    assert not AnalysisRun.objects.exists()


def test_recognition_stores_the_suggestion_and_does_not_analyse(
    client, world, exercises, queued, django_capture_on_commit_callbacks
):
    squat, _ = exercises
    client.force_login(world.patient_user)
    upload_without_exercise(client, django_capture_on_commit_callbacks)
    recording = Recording.objects.get()
    assert recognise(str(recording.pk)) == "done"
    recording.refresh_from_db()
    assert recording.suggested_exercise == squat and recording.recognition == "done"
    assert recording.recognition_progress == 100 and recording.suggestion_distance is not None
    assert not AnalysisRun.objects.exists() and queued["analyse"] == []
    assert recognise(str(recording.pk)) == "skipped", "a message delivered twice does nothing"


def test_recognition_runs_as_a_task_on_the_analyses_queue(world, exercises):
    from workers.celery import app
    from workers.tasks import recognise_exercise

    _, abduction = exercises
    recording = stored_without_exercise(world, ABDUCTION)
    route = app.amqp.router.route({}, recognise_exercise.name)
    assert route["queue"].name == app.conf.task_default_queue == "analyses"
    recognise_exercise.apply(args=[str(recording.pk)])
    recording.refresh_from_db()
    assert recording.suggested_exercise == abduction


def stored_without_exercise(world, source: str) -> Recording:
    from webapp.recordings.uploads import parse_upload, store_recording

    parsed = parse_upload(SimpleUploadedFile("t.bvh.gz", fixture_bytes(source)))
    recording, _ = store_recording(
        parsed, patient=world.patient, exercise=None, user=world.therapist
    )
    assert recording.recognition == "queued"
    return recording


def test_recognition_reports_its_progress(world, exercises, monkeypatch):
    from workers import recognition

    recording = stored_without_exercise(world, SQUAT)
    reported: list[int] = []
    real_report = recognition.report

    def keep(recording_id: str, percent: float) -> None:
        reported.append(int(percent))
        real_report(recording_id, percent)

    monkeypatch.setattr(recognition, "report", keep)
    recognise(str(recording.pk))
    # Read the file, then each of the two tutors' features; the end sets 100.
    assert reported == [10, 52, 95]
    recording.refresh_from_db()
    assert recording.recognition_progress == 100


def test_only_prescribed_exercises_are_candidates(world, exercises):
    squat, abduction = exercises
    prescribe(world.patient, abduction)
    prescribe(world.patient, squat, end_date=datetime.date.today() - datetime.timedelta(days=1))
    recording = stored_without_exercise(world, SQUAT)
    recognise(str(recording.pk))
    recording.refresh_from_db()
    # A squat, but the only current prescription is the abduction: that is the suggestion.
    assert recording.suggested_exercise == abduction


def test_page_shows_progress_then_the_suggestion_to_confirm(client, world, exercises):
    squat, abduction = exercises
    recording = stored_without_exercise(world, SQUAT)
    client.force_login(world.patient_user)
    url = reverse("recordings:detail", kwargs={"pk": recording.pk})
    waiting = client.get(url).content.decode()
    assert "Finding out which exercise this is" in waiting and 'id="recognition"' in waiting
    Recording.objects.filter(pk=recording.pk).update(recognition="running", recognition_progress=40)
    status = client.get(reverse("recordings:status", kwargs={"pk": recording.pk})).json()
    assert status == {"status": None, "stage": "", "progress": 40, "recognition": "running"}

    Recording.objects.filter(pk=recording.pk).update(recognition="queued")
    recognise(str(recording.pk))
    page = client.get(url).content.decode()
    assert "Finding out" not in page
    assert "This looks like <strong>Deep squat</strong>" in page
    assert f'name="exercise" value="{squat.pk}"' in page and "Choose another exercise" in page
    assert f'<option value="{abduction.pk}"' in page, "no prescription: every exercise offered"


def test_failed_recognition_says_so_and_offers_the_choice(client, world, exercises):
    recording = stored_without_exercise(world, SQUAT)
    recording.file.storage.delete(recording.file.name)  # the file cannot be read
    assert recognise(str(recording.pk)) == "failed"
    client.force_login(world.patient_user)
    page = client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).content.decode()
    assert "could not tell which exercise this is" in page
    assert 'id="recognition-exercise"' in page and "This looks like" not in page


def test_confirming_on_the_recording_page_queues_the_analysis(
    client, world, exercises, queued, django_capture_on_commit_callbacks
):
    squat, _ = exercises
    recording = stored_without_exercise(world, SQUAT)
    recognise(str(recording.pk))
    client.force_login(world.patient_user)
    confirm = reverse("recordings:confirm", kwargs={"pk": recording.pk})
    with django_capture_on_commit_callbacks(execute=True):
        answer = client.post(confirm, {"exercise": str(squat.pk)})
    assert answer["Location"] == reverse("recordings:detail", kwargs={"pk": recording.pk})
    run = AnalysisRun.objects.get(recording=recording)
    assert run.status == "queued" and queued["analyse"] == [str(run.pk)]
    recording.refresh_from_db()
    assert recording.exercise == squat
    assert recognise(str(recording.pk)) == "skipped", "a confirmed recording is not recognised"


def test_a_patient_is_offered_only_prescribed_exercises(client, world, exercises):
    squat, abduction = exercises
    prescribe(world.patient, abduction)
    client.force_login(world.patient_user)
    form = client.get(reverse("recordings:upload")).context["form"]
    assert list(form.fields["exercise"].queryset) == [abduction]

    recording = stored_without_exercise(world, SQUAT)
    recognise(str(recording.pk))
    page = client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).content.decode()
    assert "Shoulder abduction" in page and "Deep squat" not in page
    confirm = reverse("recordings:confirm", kwargs={"pk": recording.pk})
    refused = client.post(confirm, {"exercise": str(squat.pk)})
    assert refused.status_code == 400 and not AnalysisRun.objects.exists()


def test_api_upload_without_exercise_answers_201_at_once(
    world, exercises, queued, django_capture_on_commit_callbacks
):
    api = APIClient()
    api.force_authenticate(world.therapist)
    api.get("/api/v1/exercises/")  # a client asks which exercise ids exist first
    data = {
        "patient": str(world.patient.pk),
        "file": SimpleUploadedFile("t.bvh.gz", fixture_bytes(SQUAT)),
    }
    with django_capture_on_commit_callbacks(execute=True):
        start = time.perf_counter()
        created = api.post("/api/v1/recordings/", data, format="multipart")
        seconds = time.perf_counter() - start
    assert created.status_code == 201, created.content
    body = created.json()
    assert seconds < 1.0, f"the upload took {seconds:.2f} s"
    assert body["status"] is None and body["recognition"] == "queued"
    assert body["suggested_exercise"] is None and queued["recognise"] == [body["id"]]
