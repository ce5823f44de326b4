"""E-mail reminders of missed sessions (webapp.patients.reminders), through Django's locmem mail
backend: sent when behind this week, not when off, not twice a day, not when on track."""

from __future__ import annotations

import datetime
from io import StringIO

import pytest
from django.core import mail
from django.core.management import call_command
from django.urls import reverse
from django.utils import timezone

from tests.personas import make_exercise
from webapp.patients.models import Patient, Prescription
from webapp.patients.reminders import send_reminders, sessions_due
from webapp.recordings.models import Recording

# A Thursday: Monday to Wednesday are the days before it this week.
THURSDAY = datetime.date(2026, 11, 19)
MONDAY = THURSDAY - datetime.timedelta(days=3)


@pytest.fixture(autouse=True)
def locmem_mail(settings):
    settings.EMAIL_BACKEND = "django.core.mail.backends.locmem.EmailBackend"
    settings.DEFAULT_FROM_EMAIL = "clinic@example.org"
    settings.SITE_URL = "https://physio.example.org"


@pytest.fixture
def squat(world):
    world.patient_user.email = "ann@example.org"
    world.patient_user.save()
    Patient.objects.filter(pk=world.patient.pk).update(send_reminders=True)
    return make_exercise(world.clinic)


def prescribe(patient, exercise, per_week: int | None = 3, days: str = "") -> Prescription:
    start = THURSDAY - datetime.timedelta(days=60)
    return Prescription.objects.create(
        patient=patient, exercise=exercise, sessions_per_week=per_week, days=days, start_date=start
    )


def recorded_on(patient, exercise, day: datetime.date) -> None:
    noon = datetime.datetime.combine(day, datetime.time(12), timezone.get_current_timezone())
    recording = Recording.objects.create(
        clinic=patient.clinic, patient=patient, exercise=exercise, file="r.bvh", checksum="0"
    )
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=noon)


def test_sent_when_behind_with_exercise_names_and_counts_only(world, squat):
    prescribe(world.patient, squat, per_week=3)  # 3 × 3 days / 7: one session due by Thursday
    recorded_on(world.patient, squat, MONDAY - datetime.timedelta(days=1))  # last week's
    assert send_reminders(THURSDAY) == 1
    (message,) = mail.outbox
    assert message.to == ["ann@example.org"] and message.from_email == "clinic@example.org"
    assert message.subject == "A reminder of this week's exercises"
    assert "- Deep squat: 0 of 3 sessions this week" in message.body
    assert "https://physio.example.org" in message.body
    for private in ("Ann", "Example", "North clinic", "score", "pain"):
        assert private not in message.body
    assert Patient.objects.get(pk=world.patient.pk).last_reminder_on == THURSDAY


def test_not_sent_when_reminders_are_off(world, squat):
    Patient.objects.filter(pk=world.patient.pk).update(send_reminders=False)
    prescribe(world.patient, squat)
    world.other_patient_user.email = "bob@example.org"
    world.other_patient_user.save()
    prescribe(world.other_patient, squat)  # behind too, and off by default
    assert not Patient.objects.get(pk=world.other_patient.pk).send_reminders
    assert send_reminders(THURSDAY) == 0
    assert mail.outbox == []


def test_not_sent_twice_a_day(world, squat):
    prescribe(world.patient, squat)
    assert send_reminders(THURSDAY) == 1
    assert send_reminders(THURSDAY) == 0
    assert len(mail.outbox) == 1
    friday = THURSDAY + datetime.timedelta(days=1)
    assert send_reminders(friday) == 1  # still behind the next day: one more
    assert len(mail.outbox) == 2


def test_not_sent_when_on_track(world, squat):
    prescribe(world.patient, squat, per_week=3)
    recorded_on(world.patient, squat, MONDAY + datetime.timedelta(days=1))
    assert send_reminders(THURSDAY) == 0
    assert send_reminders(MONDAY) == 0  # nothing is due on the week's first day
    assert mail.outbox == []


def test_chosen_days_set_what_is_due(world, squat):
    plan = prescribe(world.patient, squat, per_week=3, days="mon,wed,fri")
    assert sessions_due(plan, THURSDAY) == 2  # Monday and Wednesday
    assert sessions_due(plan, MONDAY + datetime.timedelta(days=6)) == 3  # Sunday: all three
    recorded_on(world.patient, squat, MONDAY + datetime.timedelta(days=1))  # one, on Tuesday
    assert send_reminders(THURSDAY) == 1
    assert "- Deep squat: 1 of 3 sessions this week" in mail.outbox[0].body


def test_only_the_exercises_behind_are_listed(world, squat):
    shoulder = make_exercise(world.clinic, name="Shoulder raise")
    prescribe(world.patient, squat, per_week=7)  # 3 due by Thursday
    prescribe(world.patient, shoulder, per_week=2)  # 2 × 3 / 7: none due yet
    for offset in (0, 1):
        recorded_on(world.patient, squat, MONDAY + datetime.timedelta(days=offset))
    assert send_reminders(THURSDAY) == 1
    body = mail.outbox[0].body
    assert "- Deep squat: 2 of 7 sessions this week" in body and "Shoulder raise" not in body


def test_address_from_the_patient_record_and_none_for_a_closed_account(world, squat):
    Patient.objects.filter(pk=world.patient.pk).update(email="ann.home@example.org")
    prescribe(world.patient, squat)
    assert send_reminders(THURSDAY) == 1
    assert mail.outbox[0].to == ["ann.home@example.org"]
    world.patient_user.is_active = False
    world.patient_user.save()
    assert send_reminders(THURSDAY + datetime.timedelta(days=1)) == 0


def test_a_failed_send_gives_the_day_back(world, squat, settings):
    prescribe(world.patient, squat)
    settings.EMAIL_BACKEND = "tests.webapp.test_reminders.RefusingBackend"
    assert send_reminders(THURSDAY) == 0
    assert Patient.objects.get(pk=world.patient.pk).last_reminder_on is None
    settings.EMAIL_BACKEND = "django.core.mail.backends.locmem.EmailBackend"
    assert send_reminders(THURSDAY) == 1


class RefusingBackend:
    def __init__(self, *args, **kwargs) -> None:
        pass

    def send_messages(self, messages) -> int:
        raise ConnectionRefusedError("the mail server is down")


def test_therapist_turns_reminders_on_in_the_patient_form(client, world):
    assert Patient.objects.get(pk=world.patient.pk).send_reminders is False  # off by default
    client.force_login(world.therapist)
    edit = reverse("patients:edit", kwargs={"pk": world.patient.pk})
    assert "reminder when they fall behind" in client.get(edit).content.decode()
    data = {"display_name": "Ann Example", "send_reminders": "on", "email": "ann@example.org"}
    assert client.post(edit, data).status_code == 302
    patient = Patient.objects.get(pk=world.patient.pk)
    assert (patient.send_reminders, patient.email) == (True, "ann@example.org")
    page = client.get(reverse("patients:detail", kwargs={"pk": world.patient.pk}))
    assert "E-mail reminders of missed sessions: on" in page.content.decode()


def test_beat_runs_the_task_daily_and_the_command_sends_too(world, squat, settings):
    entry = settings.CELERY_BEAT_SCHEDULE["send-reminders"]
    assert entry["task"] == "workers.tasks.send_reminders"
    assert entry["schedule"].hour == {settings.REMINDER_HOUR}
    from workers.tasks import send_reminders as task

    assert task.apply().get() == 0  # nothing prescribed yet
    out = StringIO()
    call_command("send_reminders", stdout=out)
    assert out.getvalue().strip() == "Sent 0 reminders"
