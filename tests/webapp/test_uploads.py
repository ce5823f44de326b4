"""Uploading recordings through the page and the API: good files are stored and analysed once
committed; bad ones answer 400 with the reason and leave nothing behind."""

from __future__ import annotations

import gzip

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.urls import reverse
from django.utils import timezone

from tests.personas import fixture_bytes, make_exercise
from webapp.patients.models import Prescription
from webapp.recordings.models import AnalysisRun, Recording

GOOD = "reps/m01_s01_e02.bvh.gz"


@pytest.fixture
def exercise(world):
    return make_exercise(world.clinic)


def upload(client, patient, exercise, content: bytes, name: str = "take.bvh.gz", **extra):
    data = {"patient": str(patient.pk), "exercise": str(exercise.pk) if exercise else ""}
    data.update(extra)
    data["file"] = SimpleUploadedFile(name, content)
    return client.post(reverse("recordings:upload"), data)


def assert_nothing_stored(settings):
    assert Recording.objects.count() == 0
    assert AnalysisRun.objects.count() == 0
    media = settings.MEDIA_ROOT / "recordings"
    assert not media.exists() or not any(p.is_file() for p in media.rglob("*"))


def test_good_upload_is_stored_with_checksum_and_queued(client, world, exercise, monkeypatch):
    enqueued = []
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", enqueued.append)
    client.force_login(world.therapist)
    response = upload(client, world.patient, exercise, fixture_bytes(GOOD), pain_score="3")
    assert response.status_code == 302
    recording = Recording.objects.get()
    assert recording.n_frames > 10 and recording.fps == pytest.approx(30.0, rel=1e-3)
    assert len(recording.checksum) == 64
    assert recording.pain_score == 3
    run = AnalysisRun.objects.get()
    assert run.status == "queued"
    assert enqueued == [], "enqueued before the commit"


def test_patient_uploads_for_themselves(client, world, exercise, monkeypatch):
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda run_id: None)
    client.force_login(world.patient_user)
    # A patient is offered only the exercises prescribed to them (issue 18).
    assert upload(client, world.patient, exercise, fixture_bytes(GOOD)).status_code == 400
    Prescription.objects.create(
        patient=world.patient, exercise=exercise, start_date=timezone.localdate()
    )
    response = upload(client, world.patient, exercise, fixture_bytes(GOOD))
    assert response.status_code == 302
    assert Recording.objects.get().uploaded_by == world.patient_user


def test_patient_cannot_upload_for_another_patient(client, world, exercise, settings):
    client.force_login(world.patient_user)
    response = upload(client, world.other_patient, exercise, fixture_bytes(GOOD))
    assert response.status_code == 400
    assert_nothing_stored(settings)


@pytest.mark.parametrize(
    "case",
    [
        (b"HIERARCHY\nROOT Hips\n{\n", "broken.bvh", "not a readable BVH"),
        (b"%PDF-1.4 not motion at all", "scan.pdf", "Upload a BVH"),
        (b"\x00\x01\x02garbage", "take.bvh", "not a readable BVH"),
        (gzip.compress(b"MOTION\nFrames: 1\n"), "take.bvh.gz", "not a readable BVH"),
    ],
)
def test_bad_files_answer_400_and_store_nothing(client, world, exercise, settings, case):
    content, name, reason = case
    client.force_login(world.therapist)
    response = upload(client, world.patient, exercise, content, name=name)
    assert response.status_code == 400
    assert reason in response.content.decode()
    assert_nothing_stored(settings)


def test_oversize_file_is_refused(client, world, exercise, settings):
    settings.MAX_UPLOAD_BYTES = 1000
    client.force_login(world.therapist)
    response = upload(client, world.patient, exercise, fixture_bytes(GOOD))
    assert response.status_code == 400
    assert "largest accepted" in response.content.decode()
    assert_nothing_stored(settings)


def test_skeleton_mismatch_is_refused(client, world, exercise, settings):
    text = gzip.decompress(fixture_bytes(GOOD)).decode().replace("LeftFoot", "LeftPaw")
    client.force_login(world.therapist)
    response = upload(client, world.patient, exercise, text.encode(), name="take.bvh")
    assert response.status_code == 400
    assert "skeleton does not match" in response.content.decode()
    assert_nothing_stored(settings)


def test_duplicate_upload_is_detected(client, world, exercise, monkeypatch):
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda run_id: None)
    client.force_login(world.therapist)
    assert upload(client, world.patient, exercise, fixture_bytes(GOOD)).status_code == 302
    response = upload(client, world.patient, exercise, fixture_bytes(GOOD))
    assert response.status_code == 400
    assert "already uploaded" in response.content.decode()
    assert Recording.objects.count() == 1


def test_same_file_again_while_waiting_for_its_exercise_reuses_that_upload(
    client, world, exercise, monkeypatch, django_capture_on_commit_callbacks
):
    enqueued = []
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", enqueued.append)
    client.force_login(world.therapist)
    first = upload(client, world.patient, None, fixture_bytes(GOOD), pain_score="4")
    waiting = Recording.objects.get()
    assert first["Location"] == reverse("recordings:detail", kwargs={"pk": waiting.pk})
    assert waiting.exercise is None and not AnalysisRun.objects.exists()

    # Again without an exercise: the same waiting upload, with the new answers.
    again = upload(client, world.patient, None, fixture_bytes(GOOD), note="second try")
    assert again.status_code == 302 and again["Location"] == first["Location"]
    waiting.refresh_from_db()
    assert Recording.objects.count() == 1 and waiting.note == "second try"
    assert waiting.pain_score is None

    # Again with the exercise named: that upload is analysed, still one recording.
    with django_capture_on_commit_callbacks(execute=True):
        named = upload(client, world.patient, exercise, fixture_bytes(GOOD))
    assert named["Location"] == reverse("recordings:detail", kwargs={"pk": waiting.pk})
    waiting.refresh_from_db()
    assert Recording.objects.count() == 1 and waiting.exercise == exercise
    assert enqueued == [str(AnalysisRun.objects.get(recording=waiting).pk)]

    # Once it has its exercise, the same file is a duplicate again.
    refused = upload(client, world.patient, None, fixture_bytes(GOOD))
    assert refused.status_code == 400 and "already uploaded" in refused.content.decode()


def test_confirming_the_suggestion_starts_the_analysis(
    client, world, exercise, monkeypatch, django_capture_on_commit_callbacks
):
    enqueued = []
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", enqueued.append)
    client.force_login(world.therapist)
    with django_capture_on_commit_callbacks(execute=True):  # the eager recognition runs
        upload(client, world.patient, None, fixture_bytes(GOOD))
    recording = Recording.objects.get()
    confirm_url = reverse("recordings:confirm", kwargs={"pk": recording.pk})
    assert recording.suggested_exercise == exercise
    page = client.get(confirm_url)
    assert page.context["form"].initial["exercise"] == exercise.pk
    with django_capture_on_commit_callbacks(execute=True):
        answer = client.post(confirm_url, {"exercise": str(exercise.pk)})
    assert answer["Location"] == reverse("recordings:detail", kwargs={"pk": recording.pk})
    run = AnalysisRun.objects.get(recording=recording)
    assert run.status == "queued" and enqueued == [str(run.pk)]


def test_bad_answer_keeps_what_was_typed(client, world, exercise, settings):
    client.force_login(world.therapist)
    response = upload(
        client, world.patient, exercise, fixture_bytes(GOOD), pain_score="11", note="knee ok"
    )
    assert response.status_code == 400
    html = response.content.decode()
    assert "knee ok" in html and 'id="choose-again"' in html
    assert_nothing_stored(settings)
