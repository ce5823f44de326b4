"""`GET|POST /api/v1/patients/{id}/prescriptions/`: dosage in and out, validation naming the
field, clinic scope and roles; and the therapist's prescription form with the same dosage."""

from __future__ import annotations

import datetime

import pytest
from django.urls import reverse
from django.utils import timezone
from rest_framework.test import APIClient

from tests.personas import make_exercise
from webapp.patients.models import Prescription


def url(patient) -> str:
    return f"/api/v1/patients/{patient.pk}/prescriptions/"


def as_user(user) -> APIClient:
    api = APIClient()
    if user is not None:
        api.force_authenticate(user)
    return api


@pytest.fixture
def squat(world):
    return make_exercise(world.clinic)


def full_dosage(exercise) -> dict:
    return {
        "exercise": str(exercise.pk),
        "sets": 3,
        "repetitions": 12,
        "hold_seconds": 5,
        "sessions_per_week": 4,
        "days": ["fri", "mon"],
        "start_date": "2026-01-05",
        "notes": "Slowly, back straight.",
    }


def test_therapist_prescribes_a_dosage_and_reads_it_back(world, squat):
    answer = as_user(world.therapist).post(url(world.patient), full_dosage(squat), format="json")
    assert answer.status_code == 201, answer.content
    body = answer.json()
    dosage = {k: body[k] for k in ("sets", "repetitions", "hold_seconds", "sessions_per_week")}
    assert dosage == {"sets": 3, "repetitions": 12, "hold_seconds": 5, "sessions_per_week": 4}
    assert body["days"] == ["mon", "fri"]  # in week order
    stored = Prescription.objects.get(pk=body["id"])
    assert (stored.patient, stored.exercise, stored.days) == (world.patient, squat, "mon,fri")
    assert stored.start_date == datetime.date(2026, 1, 5) and stored.end_date is None
    listed = as_user(world.patient_user).get(url(world.patient)).json()
    row = listed["prescriptions"][0]
    assert (row["id"], row["repetitions"], row["notes"]) == (
        body["id"],
        12,
        "Slowly, back straight.",
    )
    assert listed["days_with_data"]["window_days"] == 30 and listed["days_with_data"]["days"] == 0
    assert len(row["adherence"]["last_4_weeks"]["weeks"]) == 4


def test_defaults_and_days_as_the_weekly_number(world, squat):
    api = as_user(world.colleague)  # any therapist of the clinic
    plain = api.post(url(world.patient), {"exercise": str(squat.pk)}, format="json").json()
    assert (plain["sessions_per_week"], plain["repetitions"], plain["sets"]) == (3, 10, None)
    assert plain["start_date"] == timezone.localdate().isoformat()
    days = {"exercise": str(squat.pk), "days": ["tue", "thu"], "repetitions": None}
    body = api.post(url(world.patient), days, format="json").json()
    assert (body["sessions_per_week"], body["repetitions"]) == (2, None)


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"sets": 0}, "sets"),
        ({"repetitions": 201}, "repetitions"),
        ({"hold_seconds": -1}, "hold_seconds"),
        ({"sessions_per_week": 8}, "sessions_per_week"),
        ({"sessions_per_week": "often"}, "sessions_per_week"),
        ({"days": ["mon", "someday"]}, "days"),
        ({"days": ["mon", "mon"]}, "days"),
        ({"end_date": "2026-01-01"}, "end_date"),
        ({"start_date": "yesterday"}, "start_date"),
        ({"exercise": "not-an-id"}, "exercise"),
    ],
)
def test_bad_dosage_answers_400_naming_the_field(world, squat, change, field):
    answer = as_user(world.therapist).post(
        url(world.patient), full_dosage(squat) | change, format="json"
    )
    assert answer.status_code == 400
    assert list(answer.json()) == [field]
    assert not Prescription.objects.exists()


def test_exercise_missing_archived_or_of_another_clinic_is_refused(world, squat):
    api = as_user(world.therapist)
    assert list(api.post(url(world.patient), {}, format="json").json()) == ["exercise"]
    elsewhere = make_exercise(world.other_clinic)
    answer = api.post(url(world.patient), {"exercise": str(elsewhere.pk)}, format="json")
    assert answer.status_code == 400 and answer.json() == {"exercise": ["Unknown exercise."]}
    squat.archived_at = timezone.now()
    squat.save()
    assert api.post(url(world.patient), {"exercise": str(squat.pk)}).status_code == 400


@pytest.mark.parametrize(
    ("persona", "patient", "statuses"),
    [
        ("therapist", "patient", (200, 201)),
        ("colleague", "patient", (200, 201)),
        ("clinic_admin", "patient", (200, 201)),
        ("patient_user", "patient", (200, 403)),  # reads their own, never prescribes
        ("other_patient_user", "patient", (404, 404)),
        ("outsider", "patient", (404, 404)),  # another clinic's patient does not exist for them
        ("therapist", "outsider_patient", (404, 404)),
        (None, "patient", (401, 401)),
    ],
)
def test_personas(world, squat, persona, patient, statuses):
    get, post = statuses
    api = as_user(getattr(world, persona) if persona else None)
    target = getattr(world, patient)
    assert api.get(url(target)).status_code == get
    answer = api.post(url(target), {"exercise": str(squat.pk)}, format="json")
    assert answer.status_code == post
    assert Prescription.objects.count() == (1 if post == 201 else 0)


def test_prescription_form_takes_the_dosage_with_plain_labels(client, world, squat):
    client.force_login(world.therapist)
    form_url = reverse("patients:prescribe", kwargs={"pk": world.patient.pk})
    page = client.get(form_url).content.decode()
    assert 'name="sessions_per_week" value="3" min="1" max="7"' in page
    for label in ("Sets per session", "Repetitions per set", "(seconds)", "Sessions per week"):
        assert label in page
    answer = client.post(
        form_url,
        {
            "exercise": squat.pk,
            "sessions_per_week": "",
            "sets": "2",
            "target_repetitions": "8",
            "hold_seconds": "10",
            "days": ["mon", "wed", "fri"],
            "start_date": "2026-01-05",
            "notes": "Hold the rail.",
        },
    )
    assert answer.status_code == 302
    stored = Prescription.objects.get()
    assert (stored.sessions_per_week, stored.days, stored.hold_seconds) == (3, "mon,wed,fri", 10)
    detail = client.get(reverse("patients:detail", kwargs={"pk": world.patient.pk}))
    text = detail.content.decode()
    assert (
        "2 sets of 8 repetitions, holding each for 10 seconds, 3 sessions a week "
        "(on Monday, Wednesday and Friday)"
    ) in text
    assert "Hold the rail." in text


def test_prescription_form_refuses_an_impossible_dosage(client, world, squat):
    client.force_login(world.therapist)
    form_url = reverse("patients:prescribe", kwargs={"pk": world.patient.pk})
    data = {"exercise": squat.pk, "sessions_per_week": "9", "start_date": "2026-01-05"}
    answer = client.post(form_url, data)
    assert answer.status_code == 200 and "less than or equal to 7" in answer.content.decode()
    assert not Prescription.objects.exists()
