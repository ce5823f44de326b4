"""E-mail reminders of missed sessions, per patient, off by default.

The beat task `workers.tasks.send_reminders` runs this daily (REMINDER_HOUR, the site's time
zone). The rule:

- Only patients whose therapist turned reminders on (`Patient.send_reminders`), not archived,
  with an address: their `email`, else their account's (a deactivated account gets none).
- The current week runs from Monday to Sunday. For each prescription active this week with a
  number of sessions per week, the sessions due by now are counted on the days before today
  within the prescription's dates: with chosen days, the chosen days among them (at most the
  sessions per week); without, sessions per week × those days / 7, rounded down. Sessions done
  are the days this week with a recording of the exercise, today included (as for adherence).
- The patient is behind when some prescription has fewer sessions done than due; one e-mail
  then lists every such exercise with the sessions done and prescribed this week. Nothing
  else: no name, score, pain or result (e-mail is not a private channel).
- At most one e-mail per patient per day: the day is claimed (`last_reminder_on`, a
  conditional UPDATE) before sending, and given back if sending fails.
"""

from __future__ import annotations

import datetime
import logging
from dataclasses import dataclass

from django.conf import settings
from django.core.mail import send_mail
from django.db.models import Prefetch, Q
from django.template.loader import render_to_string
from django.utils import timezone

from webapp.patients.adherence import count_between, session_days
from webapp.patients.models import Patient, Prescription

log = logging.getLogger(__name__)
SUBJECT = "A reminder of this week's exercises"


@dataclass(frozen=True)
class Missed:
    exercise_name: str
    sessions_done: int
    sessions_per_week: int


def week_start(today: datetime.date) -> datetime.date:
    return today - datetime.timedelta(days=today.weekday())


def sessions_due(prescription: Prescription, today: datetime.date) -> int:
    """Sessions of this week due before today (see the module's rule)."""
    first = max(week_start(today), prescription.start_date)
    last = today - datetime.timedelta(days=1)
    if prescription.end_date:
        last = min(last, prescription.end_date)
    per_week = prescription.sessions_per_week or 0
    if last < first or not per_week:
        return 0
    days = [first + datetime.timedelta(days=k) for k in range((last - first).days + 1)]
    if prescription.weekdays:
        return min(per_week, sum(1 for day in days if day.weekday() in prescription.weekdays))
    return per_week * len(days) // 7


def missed_sessions(patient: Patient, today: datetime.date) -> list[Missed]:
    """The patient's prescriptions behind this week (their `prescriptions` may be prefetched)."""
    monday = week_start(today)
    days = session_days(patient.pk, since=monday)
    missed = []
    for prescription in patient.prescriptions.all():
        done = count_between(days.get(prescription.exercise_id, ()), monday, today)
        if done < sessions_due(prescription, today):
            name = prescription.exercise.name
            missed.append(Missed(name, done, prescription.sessions_per_week or 0))
    return missed


def address(patient: Patient) -> str:
    if patient.user is not None and not patient.user.is_active:
        return ""
    return patient.email or (patient.user.email if patient.user is not None else "")


def candidates(today: datetime.date):
    """Patients with reminders on, not yet reminded today, with this week's prescriptions."""
    active = Prescription.objects.filter(start_date__lte=today).filter(
        Q(end_date__isnull=True) | Q(end_date__gte=week_start(today))
    )
    return (
        Patient.objects.filter(send_reminders=True, archived_at__isnull=True)
        .exclude(last_reminder_on=today)
        .select_related("user")
        .prefetch_related(
            Prefetch("prescriptions", queryset=active.select_related("exercise").order_by("pk"))
        )
        .order_by("pk")
    )


def claim_day(patient: Patient, today: datetime.date) -> bool:
    """Mark today's reminder as sent; False when another run already did."""
    unclaimed = Patient.objects.filter(pk=patient.pk).exclude(last_reminder_on=today)
    return unclaimed.update(last_reminder_on=today) == 1


def send_one(patient: Patient, missed: list[Missed], today: datetime.date) -> bool:
    to = address(patient)
    if not to or not claim_day(patient, today):
        return False
    context = {"missed": missed, "site_url": settings.SITE_URL}
    body = render_to_string("patients/reminder_email.txt", context)
    try:
        send_mail(SUBJECT, body, None, [to])
    except OSError:  # SMTP errors are OSErrors: try again at the next run
        log.exception("Could not send the reminder of patient %s", patient.pk)
        Patient.objects.filter(pk=patient.pk).update(last_reminder_on=patient.last_reminder_on)
        return False
    return True


def send_reminders(today: datetime.date | None = None) -> int:
    """Send today's reminders; returns how many e-mails were sent."""
    today = today or timezone.localdate()
    sent = 0
    for patient in candidates(today):
        missed = missed_sessions(patient, today)
        if missed and send_one(patient, missed, today):
            sent += 1
    return sent
