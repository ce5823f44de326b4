"""Adherence of a prescription: sessions done (days with a recording) versus prescribed."""

from __future__ import annotations

import datetime

from django.urls import reverse
from django.utils import timezone
from rest_framework.test import APIClient

from tests.personas import make_exercise, make_recording
from webapp.patients.adherence import adherence
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
