"""Data safety: uploads stored with their SHA-256 and verified on every read; deleting a patient
is a soft delete (hidden everywhere at once) purged with its files after the retention period."""

from __future__ import annotations

import hashlib
import io
from datetime import timedelta
from pathlib import Path

import pytest
from django.core.files.base import ContentFile
from django.core.files.uploadedfile import SimpleUploadedFile
from django.core.management import call_command
from django.urls import reverse
from django.utils import timezone
from rest_framework.test import APIClient

from tests.personas import PASSWORD, fixture_bytes, make_exercise, make_recording, make_world
from webapp.accounts.permissions import visible_patients, visible_recordings
from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from webapp.recordings.storage import DamagedRecordingError, read_verified
from webapp.recordings.uploads import parse_upload, store_recording
from workers.analysis_task import analyse_run

SOURCE = "reps/m01_s01_e02.bvh.gz"


@pytest.fixture
def world(db, settings, tmp_path):
    settings.MEDIA_ROOT = tmp_path / "media"
    return make_world()


@pytest.fixture
def exercise(world):
    return make_exercise(world.clinic)


def damage(recording: Recording) -> None:
    path = Path(recording.file.path)
    content = bytearray(path.read_bytes())
    content[len(content) // 2] ^= 0xFF  # one flipped byte
    path.write_bytes(bytes(content))


def test_upload_is_stored_with_the_sha256_of_its_bytes(world):
    upload = SimpleUploadedFile("session.bvh.gz", fixture_bytes(SOURCE))
    recording, _ = store_recording(
        parse_upload(upload), patient=world.patient, exercise=None, user=world.therapist
    )
    with recording.file.open("rb") as handle:
        stored = handle.read()
    assert recording.checksum == hashlib.sha256(stored).hexdigest()
    assert read_verified(recording) == fixture_bytes(SOURCE)
    assert recording.damaged_at is None


def test_changed_file_fails_its_run_with_a_reason_and_marks_the_recording(world, exercise):
    recording = make_recording(world.patient, exercise, SOURCE)
    damage(recording)
    with pytest.raises(DamagedRecordingError, match="damaged"):
        read_verified(recording)
    run = recording.runs.get()
    assert analyse_run(str(run.pk)) == "failed"
    run.refresh_from_db()
    recording.refresh_from_db()
    assert run.status == RunStatus.FAILED and "damaged" in run.user_error
    assert "SHA-256" in run.user_error and "backup" in run.user_error
    assert recording.damaged_at is not None and "differs" in recording.damage


def test_missing_file_is_reported_as_damage(world, exercise):
    recording = make_recording(world.patient, exercise, SOURCE)
    recording.file.storage.delete(recording.file.name)
    run = recording.runs.get()
    assert analyse_run(str(run.pk)) == "failed"
    recording.refresh_from_db()
    assert recording.damage == "the stored file is missing"


def test_confirm_page_answers_the_damage_instead_of_crashing(world, exercise, client):
    recording = make_recording(world.patient, None, SOURCE)
    damage(recording)
    client.force_login(world.therapist)
    url = reverse("recordings:confirm", args=[recording.pk])
    response = client.post(url, {"exercise": str(exercise.pk)})
    assert response.status_code == 400
    assert "damaged" in response.content.decode()


def api_client(user) -> APIClient:
    client = APIClient()
    client.force_authenticate(user)
    return client


def test_deleted_patient_is_hidden_from_every_list_and_api(world, exercise, client):
    recording = make_recording(world.patient, exercise, SOURCE)
    patient = world.patient
    patient.delete()

    assert Patient.objects.filter(pk=patient.pk).count() == 0
    assert Patient.all_objects.get(pk=patient.pk).deleted_at is not None
    assert patient not in visible_patients(world.therapist)
    assert recording not in visible_recordings(world.therapist)
    assert not world.therapist.assigned_patients.exists()
    client.force_login(world.therapist)
    for page in ("patients:list", "dashboard:home"):
        assert patient.display_name not in client.get(reverse(page)).content.decode()
    assert client.get(reverse("patients:detail", args=[patient.pk])).status_code == 404
    api = api_client(world.therapist)
    listed = api.get("/api/v1/patients/").json()
    assert str(patient.pk) not in str(listed) and patient.display_name not in str(listed)
    assert api.get(f"/api/v1/patients/{patient.pk}/").status_code == 404
    assert api.get(f"/api/v1/patients/{patient.pk}/recordings/").status_code == 404
    assert api.get(f"/api/v1/recordings/{recording.pk}/").status_code == 404
    # The patient's own login is switched off with the record.
    world.patient_user.refresh_from_db()
    assert not world.patient_user.is_active
    assert not client.login(username="patient", password=PASSWORD)


def test_bulk_delete_is_soft_too(world):
    assert Patient.objects.filter(clinic=world.clinic).delete()[0] == 2
    assert Patient.all_objects.filter(clinic=world.clinic, deleted_at__isnull=False).count() == 2
    assert Patient.objects.filter(clinic=world.clinic).count() == 0


def with_arrays(recording: Recording) -> AnalysisRun:
    run = recording.runs.get()
    run.arrays.save("r.npz", ContentFile(b"result arrays"), save=True)
    return run


def test_purge_after_retention_deletes_rows_and_files(world, exercise, settings):
    settings.PATIENT_RETENTION_DAYS = 30
    old = make_recording(world.patient, exercise, SOURCE)
    recent = make_recording(world.other_patient, exercise, SOURCE)
    old_files = [Path(old.file.path), Path(with_arrays(old).arrays.path)]
    world.patient.delete()
    world.other_patient.delete()
    long_ago = timezone.now() - timedelta(days=31)
    Patient.all_objects.filter(pk=world.patient.pk).update(deleted_at=long_ago)
    Patient.all_objects.filter(pk=world.other_patient.pk).update(
        deleted_at=timezone.now() - timedelta(days=10)
    )

    out = io.StringIO()
    call_command("purge_deleted_patients", "--dry-run", stdout=out)
    assert out.getvalue().startswith("1 patients")
    assert all(path.exists() for path in old_files)
    call_command("purge_deleted_patients", stdout=out)

    assert "Purged 1 patients" in out.getvalue()
    assert not Patient.all_objects.filter(pk=world.patient.pk).exists()
    assert not Recording.all_objects.filter(pk=old.pk).exists()
    assert not AnalysisRun.objects.filter(recording_id=old.pk).exists()
    assert not any(path.exists() for path in old_files)
    # Still within its retention period: kept, hidden, with its file.
    assert Patient.all_objects.filter(pk=world.other_patient.pk).exists()
    assert Path(Recording.all_objects.get(pk=recent.pk).file.path).exists()
