"""One clinic-scope guard (`webapp.accounts.permissions.clinic_scoped`) decides what every view
family may show (issue 22, item 4): another clinic's object is 404 through the pages of
patients, recordings, exercises, reports and live sessions and through the API, and each family
reaches its objects through that one helper."""

from __future__ import annotations

import pytest
from django.test import Client
from django.urls import reverse
from rest_framework.test import APIClient

from tests.personas import make_exercise, make_recording
from webapp.accounts import permissions
from webapp.accounts.models import User
from webapp.live import services
from webapp.live.models import LiveSession
from webapp.patients.models import Patient
from webapp.recordings.models import Recording

# (URL name, which object it names): one or more routes of each view family.
PAGES = [
    ("patients:detail", "patient"),
    ("reports:progress", "patient"),
    ("recordings:detail", "recording"),
    ("reports:recording-print", "recording"),
    ("exercises:detail", "exercise"),
    ("live:page", "live"),
]
API = [("api-patient", "patient"), ("api-recording", "recording")]


def objects_of(clinic_patient: Patient, therapist: User) -> dict:
    exercise = make_exercise(clinic_patient.clinic)
    live = LiveSession.objects.create(
        clinic=clinic_patient.clinic, patient=clinic_patient, exercise=exercise,
        created_by=therapist,
    )  # fmt: skip
    recording = make_recording(clinic_patient, exercise)
    return {"patient": clinic_patient, "exercise": exercise, "recording": recording, "live": live}


@pytest.fixture
def elsewhere(world) -> dict:
    """A patient, exercise, recording and live session of the other clinic."""
    return objects_of(world.outsider_patient, world.outsider)


@pytest.fixture
def here(world) -> dict:
    return objects_of(world.patient, world.therapist)


def page_status(user: User, name: str, target) -> int:
    client = Client()
    client.force_login(user)
    return client.get(reverse(name, kwargs={"pk": target.pk})).status_code


def api_status(user: User, name: str, target) -> int:
    client = APIClient()
    client.force_authenticate(user)
    return client.get(reverse(name, kwargs={"pk": target.pk})).status_code


@pytest.mark.parametrize(("name", "target"), PAGES)
def test_another_clinics_object_is_404_on_every_page_family(world, elsewhere, name, target):
    assert page_status(world.therapist, name, elsewhere[target]) == 404
    assert page_status(world.outsider, name, elsewhere[target]) != 404  # it exists over there


@pytest.mark.parametrize(("name", "target"), API)
def test_another_clinics_object_is_404_through_the_api(world, elsewhere, name, target):
    assert api_status(world.therapist, name, elsewhere[target]) == 404
    assert api_status(world.outsider, name, elsewhere[target]) == 200


def test_a_live_session_cannot_be_opened_on_another_clinics_exercise(world, elsewhere):
    client = APIClient()
    client.force_authenticate(world.therapist)
    body = {"patient": str(world.patient.pk), "exercise": str(elsewhere["exercise"].pk)}
    assert client.post("/api/v1/live-sessions/", body).status_code == 404
    assert not LiveSession.objects.filter(patient=world.patient).exists()


@pytest.fixture
def scoped_models(monkeypatch) -> list[str]:
    """The names of the models each request scoped through the one helper."""
    seen: list[str] = []
    helper = permissions.clinic_scoped

    def spy(rows, user, own=None):
        seen.append(rows.model.__name__)
        return helper(rows, user, own)

    monkeypatch.setattr(permissions, "clinic_scoped", spy)
    monkeypatch.setattr(services, "clinic_scoped", spy)
    return seen


SCOPED = [
    ("patients:detail", "patient", "Patient"),
    ("recordings:detail", "recording", "Recording"),
    ("exercises:detail", "exercise", "Exercise"),
    ("reports:recording-print", "recording", "Recording"),
    ("live:page", "live", "LiveSession"),
]


@pytest.mark.parametrize("case", SCOPED, ids=lambda case: case[0])
def test_each_page_family_scopes_through_the_one_helper(world, here, scoped_models, case):
    name, target, model = case
    assert page_status(world.therapist, name, here[target]) == 200
    assert model in scoped_models


@pytest.mark.parametrize("persona", ["patient_user", "therapist"])
def test_the_helper_gives_a_patient_their_own_rows_and_staff_the_clinics(world, here, persona):
    other = make_recording(world.other_patient, here["exercise"])
    user = getattr(world, persona)
    mine = permissions.clinic_scoped(Recording.objects.all(), user, own="patient__user")
    expected = (
        {here["recording"].pk} if persona == "patient_user" else {here["recording"].pk, other.pk}
    )
    assert set(mine.values_list("pk", flat=True)) == expected


def test_the_helper_gives_no_rows_to_an_account_without_a_clinic(world, here):
    world.therapist.clinic = None
    assert not permissions.clinic_scoped(Patient.objects.all(), world.therapist).exists()
