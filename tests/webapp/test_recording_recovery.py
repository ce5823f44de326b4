"""Recovering from a mistaken upload (issue 25, item 4): staff move a recording to another
exercise or patient of the clinic (analysed again) and delete one (soft, audited, hidden from every
list); a clinic admin restores it. An exercise without key poses cannot be chosen for an upload."""

from __future__ import annotations

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.test import Client
from django.urls import reverse
from django.utils import timezone
from rest_framework.test import APIClient

from tests.personas import fixture_bytes, make_exercise, make_recording
from webapp.audit.models import AuditEvent
from webapp.dashboard.models import PatientAttention
from webapp.dashboard.precompute import refresh_patient
from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun, Recording, RunStatus


@pytest.fixture
def setup(world, monkeypatch):
    """Two exercises of the clinic (one without key poses), one recording of Ann's."""
    queued: list[str] = []
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", queued.append)
    squat = make_exercise(world.clinic)
    abduction = make_exercise(world.clinic, name="Shoulder abduction")
    bare = make_exercise(world.clinic, name="Lunge")
    bare.tutor_landmark_frames, bare.tutor_landmark_types = [], []
    bare.save()
    recording = make_recording(world.patient, squat)
    return {"squat": squat, "abduction": abduction, "bare": bare, "recording": recording}


def api_as(user) -> APIClient:
    client = APIClient()
    client.force_authenticate(user)
    return client


def events(recording, action: str):
    return AuditEvent.objects.filter(
        object_type="Recording", object_id=str(recording.pk), action=action
    )


def url(recording) -> str:
    return f"/api/v1/recordings/{recording.pk}/"


def test_api_patch_moves_to_another_exercise_and_queues_a_new_run(world, setup):
    recording, abduction = setup["recording"], setup["abduction"]
    answer = api_as(world.therapist).patch(
        url(recording), {"exercise": str(abduction.pk)}, format="json"
    )
    assert answer.status_code == 200, answer.content
    body = answer.json()
    assert body["exercise"] == str(abduction.pk) and body["status"] == "queued"
    recording.refresh_from_db()
    assert recording.exercise_id == abduction.pk
    runs = list(recording.runs.order_by("created_at"))
    assert len(runs) == 2 and runs[-1].status == RunStatus.QUEUED  # the first run is kept
    assert str(runs[-1].pk) == body["run"]["id"]
    (event,) = events(recording, "update")
    assert (event.username, event.patient_id) == ("therapist", world.patient.pk)
    assert AuditEvent.objects.filter(action="create", object_type="AnalysisRun").exists()


def test_api_patch_moves_to_another_patient_audited_for_both(world, setup):
    recording = setup["recording"]
    answer = api_as(world.colleague).patch(
        url(recording), {"patient": str(world.other_patient.pk)}, format="json"
    )
    assert answer.status_code == 200, answer.content
    assert answer.json()["patient"] == str(world.other_patient.pk)
    assert recording.runs.count() == 2
    assert {e.patient_id for e in events(recording, "update")} == {
        world.patient.pk,
        world.other_patient.pk,
    }
    assert not world.patient.recordings.exists()
    assert list(world.other_patient.recordings.all()) == [recording]


def test_api_patch_refuses_bad_input_with_a_message(world, setup):
    recording, api = setup["recording"], api_as(world.therapist)
    elsewhere = make_exercise(world.other_clinic, name="Elsewhere")
    cases = [
        ({"exercise": "not-an-id"}, "exercise", "valid UUID"),
        ({"exercise": str(elsewhere.pk)}, "exercise", "Unknown exercise"),
        ({"patient": str(world.outsider_patient.pk)}, "patient", "Unknown patient"),
        ({"exercise": str(setup["bare"].pk)}, "exercise", "has no key poses yet"),
        ({}, "__all__", "Choose the exercise or the patient"),
    ]
    for data, field, words in cases:
        answer = api.patch(url(recording), data, format="json")
        assert answer.status_code == 400, data
        assert words in str(answer.json()[field]), answer.json()
    recording.refresh_from_db()
    assert recording.exercise_id == setup["squat"].pk and recording.runs.count() == 1
    assert not events(recording, "update").exists()


def test_api_patch_with_nothing_to_change_queues_nothing(world, setup):
    recording = setup["recording"]
    answer = api_as(world.therapist).patch(
        url(recording), {"exercise": str(setup["squat"].pk)}, format="json"
    )
    assert answer.status_code == 200 and recording.runs.count() == 1


def test_api_delete_hides_the_recording_everywhere(world, setup):
    recording, api = setup["recording"], api_as(world.therapist)
    assert api.delete(url(recording)).status_code == 204
    row = Recording.all_objects.get(pk=recording.pk)
    assert row.deleted_at is not None and row.deleted_by == world.therapist
    (event,) = events(recording, "delete")
    assert (event.username, event.patient_id) == ("therapist", world.patient.pk)
    assert api.get(url(recording)).status_code == 404
    assert api.delete(url(recording)).status_code == 404
    listed = api.get(f"/api/v1/patients/{world.patient.pk}/recordings/").json()
    assert listed["results"] == []
    client = Client()
    client.force_login(world.therapist)
    page = client.get(reverse("patients:detail", kwargs={"pk": world.patient.pk}))
    assert reverse("recordings:detail", kwargs={"pk": recording.pk}) not in page.content.decode()
    assert client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).status_code == 404


@pytest.mark.parametrize("method", ["patch", "delete"])
def test_api_patients_cannot_move_or_delete_and_other_clinics_get_404(world, setup, method):
    recording, target = setup["recording"], {"exercise": str(setup["abduction"].pk)}
    expected = {"patient_user": 403, "other_patient_user": 404, "outsider": 404}
    for persona, status in expected.items():
        answer = getattr(api_as(getattr(world, persona)), method)(
            url(recording), target, format="json"
        )
        assert answer.status_code == status, persona
    row = Recording.all_objects.get(pk=recording.pk)
    assert row.deleted_at is None and row.exercise_id == setup["squat"].pk
    assert AuditEvent.objects.filter(action__in=["update", "delete"]).count() == 0


def test_progress_and_history_leave_deleted_recordings_out(world, setup):
    recording = setup["recording"]
    from webapp.recordings.services import analyse_now

    analyse_now(recording.runs.get())
    api = api_as(world.therapist)
    progress = f"/api/v1/patients/{world.patient.pk}/progress/"
    history = f"/api/v1/patients/{world.patient.pk}/history.csv"
    assert len(api.get(progress).json()["points"]) == 1
    assert len(api.get(history).content.decode().strip().splitlines()) == 2
    api.delete(url(recording))
    assert api.get(progress).json()["points"] == []
    assert len(api.get(history).content.decode().strip().splitlines()) == 1  # the header
    fhir = api.get(f"/api/v1/patients/{world.patient.pk}/fhir/").json()
    assert [e for e in fhir["entry"] if e["resource"]["resourceType"] == "Observation"] == []


def failed(recording) -> None:
    AnalysisRun.objects.filter(recording=recording).update(
        status=RunStatus.FAILED, user_error="broken", finished_at=timezone.now()
    )
    refresh_patient(recording.patient_id, recording.clinic_id)
    assert PatientAttention.objects.filter(patient_id=recording.patient_id).exists()


def test_a_failed_recording_leaves_the_attention_list_once_moved_or_deleted(world, setup):
    recording, api = setup["recording"], api_as(world.therapist)
    failed(recording)
    api.patch(url(recording), {"exercise": str(setup["abduction"].pk)}, format="json")
    assert not PatientAttention.objects.filter(patient=world.patient).exists()
    failed(recording)  # the new run fails too
    api.delete(url(recording))
    assert not PatientAttention.objects.filter(patient=world.patient).exists()


def test_pages_move_then_delete_with_confirmation_then_admin_restores(world, setup, client):
    recording, abduction = setup["recording"], setup["abduction"]
    client.force_login(world.therapist)
    detail = reverse("recordings:detail", kwargs={"pk": recording.pk})
    page = client.get(detail).content.decode()
    assert 'id="move-form"' in page and "Shoulder abduction" in page
    assert "Lunge" not in page  # no key poses: not offered
    move = reverse("recordings:move", kwargs={"pk": recording.pk})
    answer = client.post(move, {"exercise": abduction.pk, "patient": world.patient.pk})
    assert answer.status_code == 302 and answer["Location"] == detail
    assert Recording.objects.get(pk=recording.pk).exercise_id == abduction.pk
    assert recording.runs.count() == 2 and events(recording, "update").count() == 1
    delete = reverse("recordings:delete", kwargs={"pk": recording.pk})
    confirm = client.get(delete)
    assert confirm.status_code == 200 and "Delete this recording?" in confirm.content.decode()
    assert Recording.objects.filter(pk=recording.pk).exists()  # asking deletes nothing
    assert client.post(delete).status_code == 302
    assert not Recording.objects.filter(pk=recording.pk).exists()
    assert events(recording, "delete").count() == 1
    assert client.get(reverse("recordings:deleted")).status_code == 403  # admins only
    client.force_login(world.clinic_admin)
    listed = client.get(reverse("recordings:deleted")).content.decode()
    assert "Ann Example" in listed and "Shoulder abduction" in listed
    restore = reverse("recordings:restore", kwargs={"pk": recording.pk})
    assert client.post(restore).status_code == 302
    assert Recording.objects.filter(pk=recording.pk).exists()
    (event,) = events(recording, "update").filter(username="clinic-admin")
    assert event.path == restore and event.patient_id == world.patient.pk
    assert client.post(restore).status_code == 404  # nothing left to restore


def test_the_move_page_says_why_a_move_is_refused(world, setup, client):
    recording = setup["recording"]
    Patient.objects.filter(pk=world.other_patient.pk).update(archived_at=timezone.now())
    client.force_login(world.therapist)
    move = reverse("recordings:move", kwargs={"pk": recording.pk})
    answer = client.post(move, {"patient": world.other_patient.pk})
    assert answer.status_code == 400 and "Unknown patient" in answer.content.decode()
    client.force_login(world.patient_user)
    assert client.post(move, {"exercise": setup["abduction"].pk}).status_code == 403


def test_an_exercise_without_key_poses_cannot_be_chosen_for_an_upload(world, setup, client):
    bare = setup["bare"]
    client.force_login(world.therapist)
    form = client.get(reverse("recordings:upload")).content.decode()
    assert "Shoulder abduction" in form and "Lunge" not in form
    upload = SimpleUploadedFile("take.bvh.gz", fixture_bytes("reps/m01_s01_e03.bvh.gz"))
    answer = api_as(world.therapist).post(
        "/api/v1/recordings/",
        {"patient": str(world.patient.pk), "exercise": str(bare.pk), "file": upload},
        format="multipart",
    )
    assert answer.status_code == 400
    (message,) = [e["message"] for e in answer.json()["exercise"]]
    assert message.startswith("Lunge has no key poses yet")
    assert not Recording.objects.filter(exercise=bare).exists()


def test_corrections_of_a_moved_or_deleted_recording_train_no_model(world, setup):
    """A therapist's corrections speak of the exercise the run was analysed with: once the
    recording moves to another exercise they train neither; once deleted, nothing."""
    from webapp.exercises.models import ExerciseModel
    from webapp.recordings.models import LandmarkCorrection
    from workers.training import corrected_runs

    recording, squat, abduction = setup["recording"], setup["squat"], setup["abduction"]
    run = recording.runs.get()
    run.model = ExerciseModel.objects.create_next_version(squat)
    run.save()
    LandmarkCorrection.objects.create(run=run, frames=[0, 40], types=[1, 2])
    other = make_recording(world.patient, squat, source="reps/m01_s01_e03.bvh.gz")
    LandmarkCorrection.objects.create(run=other.runs.get(), frames=[0, 40], types=[1, 2])
    assert set(corrected_runs(squat)) == {run, other.runs.get()}
    api = api_as(world.therapist)
    api.patch(url(recording), {"exercise": str(abduction.pk)}, format="json")
    assert list(corrected_runs(abduction)) == [] and list(corrected_runs(squat)) == [
        other.runs.get()
    ]
    api.delete(url(other))
    assert list(corrected_runs(squat)) == []
