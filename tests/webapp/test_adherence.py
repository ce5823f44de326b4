"""Adherence of a prescription: sessions done (days with a recording) versus prescribed."""

from __future__ import annotations

import datetime

from django.urls import reverse
from django.utils import timezone
from rest_framework.test import APIClient

from tests.personas import make_exercise, make_recording
from webapp.patients.adherence import adherence, patient_adherence
from webapp.patients.models import Prescription
from webapp.recordings.models import Recording


def recorded(patient, exercise, days_ago: int, source: str) -> None:
    recording = make_recording(patient, exercise, source=source)
    when = timezone.now() - datetime.timedelta(days=days_ago)
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when)


def test_sessions_done_versus_prescribed(world):
    exercise = make_exercise(world.clinic)
    today = timezone.localdate()
    prescription = Prescription.objects.create(
        patient=world.patient,
        exercise=exercise,
        sessions_per_week=3,
        start_date=today - datetime.timedelta(days=13),
    )
    recorded(world.patient, exercise, 10, "reps/m01_s01_e01.bvh.gz")
    recorded(world.patient, exercise, 3, "reps/m01_s01_e02.bvh.gz")
    recorded(world.patient, exercise, 3, "reps/m01_s01_e03.bvh.gz")  # same day: one session
    recorded(world.patient, exercise, 30, "reps/m01_s01_e02_inc.bvh.gz")  # before the start
    recorded(world.other_patient, exercise, 2, "reps/m01_s01_e03_inc.bvh.gz")  # someone else
    result = adherence(prescription, today)
    assert result.sessions_prescribed == 6  # two weeks at 3 per week
    assert result.sessions_done == 2
    assert result.percent == 33.3


def test_future_and_ended_prescriptions(world):
    exercise = make_exercise(world.clinic)
    today = timezone.localdate()
    future = Prescription.objects.create(
        patient=world.patient, exercise=exercise, start_date=today + datetime.timedelta(days=3)
    )
    assert adherence(future, today).sessions_prescribed == 0
    assert adherence(future, today).percent is None
    ended = Prescription.objects.create(
        patient=world.patient,
        exercise=exercise,
        sessions_per_week=7,
        start_date=today - datetime.timedelta(days=60),
        end_date=today - datetime.timedelta(days=54),
    )
    assert adherence(ended, today).sessions_prescribed == 7


def test_adherence_on_the_page_and_in_the_api(client, world):
    exercise = make_exercise(world.clinic)
    Prescription.objects.create(
        patient=world.patient,
        exercise=exercise,
        sessions_per_week=7,
        start_date=timezone.localdate(),
    )
    recorded(world.patient, exercise, 0, "reps/m01_s01_e01.bvh.gz")
    client.force_login(world.therapist)
    page = client.get(reverse("patients:detail", kwargs={"pk": world.patient.pk}))
    assert "1 of 1 session done (100%)" in page.content.decode()
    api = APIClient()
    api.force_authenticate(world.patient_user)
    body = api.get(f"/api/v1/patients/{world.patient.pk}/prescriptions/").json()
    assert body["prescriptions"][0]["adherence"]["sessions_done"] == 1
    api.force_authenticate(world.other_patient_user)
    assert api.get(f"/api/v1/patients/{world.patient.pk}/prescriptions/").status_code == 404


# A constructed history: the last 4 weeks are days_ago 27..21, 20..14, 13..7 and 6..0.
SQUAT_DAYS = (35, 27, 25, 25, 23, 22, 20, 6, 2)  # 25 twice: one session
SHOULDER_DAYS = (29, 10, 6)  # 29 is before its prescription starts
UNCONFIRMED_DAYS = (12,)  # a recording whose exercise is still to confirm


def quick_recording(patient, exercise, days_ago: int) -> None:
    """A recording row only (no file): adherence reads the upload day and nothing else."""
    when = timezone.now() - datetime.timedelta(days=days_ago)
    recording = Recording.objects.create(
        clinic=patient.clinic, patient=patient, exercise=exercise, file="r.bvh", checksum="0"
    )
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when)


def constructed_history(world):
    squat = make_exercise(world.clinic)
    shoulder = make_exercise(world.clinic, name="Shoulder raise")
    today = timezone.localdate()
    squat_plan = Prescription.objects.create(
        patient=world.patient,
        exercise=squat,
        sessions_per_week=3,
        sets=2,
        target_repetitions=10,
        start_date=today - datetime.timedelta(days=40),
    )
    shoulder_plan = Prescription.objects.create(
        patient=world.patient,
        exercise=shoulder,
        sessions_per_week=2,
        start_date=today - datetime.timedelta(days=10),
    )
    for exercise, days in (
        (squat, SQUAT_DAYS),
        (shoulder, SHOULDER_DAYS),
        (None, UNCONFIRMED_DAYS),
    ):
        for days_ago in days:
            quick_recording(world.patient, exercise, days_ago)
    quick_recording(world.other_patient, squat, 1)  # someone else's
    return squat_plan, shoulder_plan, today


def test_last_four_weeks_against_the_dosage(world):
    squat_plan, shoulder_plan, today = constructed_history(world)
    squat = adherence(squat_plan, today)
    # Since the start (41 days at 3 a week): 18 prescribed; 8 days with a session.
    assert (squat.sessions_prescribed, squat.sessions_done, squat.percent) == (18, 8, 44.4)
    recent = squat.last_4_weeks
    weeks = [(w.sessions_prescribed, w.sessions_done) for w in recent.weeks]
    assert weeks == [(3, 4), (3, 1), (3, 0), (3, 2)]
    assert recent.first == today - datetime.timedelta(days=27) and recent.last == today
    # The first week's fourth session does not make up for the third week's none.
    assert (recent.sessions_prescribed, recent.sessions_done, recent.percent) == (12, 6, 50.0)
    shoulder = adherence(shoulder_plan, today).last_4_weeks
    # Active only the last 11 days: 4 of week three's days (ceil(2 × 4 / 7) = 2), all of week four.
    assert [(w.sessions_prescribed, w.sessions_done) for w in shoulder.weeks] == [
        (0, 0),
        (0, 0),
        (2, 1),
        (2, 1),
    ]
    assert (shoulder.sessions_prescribed, shoulder.sessions_done, shoulder.percent) == (4, 2, 50.0)


def test_days_with_data_in_the_last_30_days(world):
    _, _, today = constructed_history(world)
    found, days = patient_adherence(world.patient, today)
    # Squat 27 25 23 22 20 6 2, shoulder 29 10 (6 again), unconfirmed 12; not 35, not Bob's.
    assert days.days == 10
    assert (days.first, days.last, days.window_days) == (
        today - datetime.timedelta(days=29),
        today,
        30,
    )
    assert [a.exercise_name for a in found] == ["Shoulder raise", "Deep squat"]  # newest first
    squat = Prescription.objects.select_related("exercise").get(pk=found[1].prescription)
    assert found[1] == adherence(squat, today)  # the same figures as one prescription's read


def test_one_query_for_every_prescription_and_the_days_with_data(world, django_assert_num_queries):
    constructed_history(world)
    prescriptions = list(world.patient.prescriptions.select_related("exercise"))
    with django_assert_num_queries(1):
        patient_adherence(world.patient, prescriptions=prescriptions)


def test_dosage_and_recent_adherence_on_the_pages(client, world):
    constructed_history(world)
    client.force_login(world.therapist)
    page = client.get(reverse("patients:detail", kwargs={"pk": world.patient.pk})).content.decode()
    assert "2 sets of 10 repetitions, 3 sessions a week" in page
    assert "Days with data in the last 30 days" in page and "<strong>10</strong> of 30" in page
    assert "6 of 12 sessions done (50%)" in page
    assert "Week by week, oldest first: 4 of 3 · 1 of 3 · 0 of 3 · 2 of 3" in page
    client.force_login(world.patient_user)
    home = client.get(reverse("dashboard:home")).content.decode()
    assert "2 sets of 10 repetitions, 3 sessions a week" in home
    assert "Last 4 weeks: 6 of 12 sessions done" in home
    assert "<strong>10</strong> of 30" in home
