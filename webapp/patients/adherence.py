"""Adherence: sessions done versus sessions prescribed, per prescription.

Prescribed sessions are `sessions_per_week` × the weeks (fractional) the prescription has been
active up to today (or its end date). A session is a day with at least one recording of the
exercise by the patient within the prescription's dates: several uploads on one day count once,
as the patient exercised once.
"""

from __future__ import annotations

import datetime
import math
from dataclasses import asdict, dataclass
from typing import Any, Protocol

from django.utils import timezone

from webapp.patients.models import Prescription
from webapp.recordings.models import Recording


class PrescribedPeriod(Protocol):
    """What counting prescribed sessions needs: a `Prescription`, or a period built from one."""

    @property
    def start_date(self) -> datetime.date: ...

    @property
    def end_date(self) -> datetime.date | None: ...

    @property
    def sessions_per_week(self) -> int: ...


@dataclass(frozen=True)
class Adherence:
    prescription: str
    exercise: str
    exercise_name: str
    sessions_prescribed: int
    sessions_done: int
    percent: float | None  # None before the first prescribed session is due

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


def prescribed_sessions(prescription: PrescribedPeriod, today: datetime.date) -> int:
    end = min(today, prescription.end_date) if prescription.end_date else today
    days = (end - prescription.start_date).days + 1
    if days <= 0:
        return 0
    return math.ceil(prescription.sessions_per_week * days / 7)


def sessions_done(prescription: Prescription, today: datetime.date) -> int:
    end = min(today, prescription.end_date) if prescription.end_date else today
    days = Recording.objects.filter(
        patient_id=prescription.patient_id,
        exercise_id=prescription.exercise_id,
        uploaded_at__date__gte=prescription.start_date,
        uploaded_at__date__lte=end,
    ).dates("uploaded_at", "day")
    return days.count()


def adherence(prescription: Prescription, today: datetime.date | None = None) -> Adherence:
    today = today or timezone.localdate()
    expected = prescribed_sessions(prescription, today)
    done = sessions_done(prescription, today)
    return Adherence(
        prescription=str(prescription.pk),
        exercise=str(prescription.exercise_id),
        exercise_name=prescription.exercise.name,
        sessions_prescribed=expected,
        sessions_done=done,
        percent=round(100.0 * min(done, expected) / expected, 1) if expected else None,
    )


def patient_adherence(patient) -> list[Adherence]:
    prescriptions = patient.prescriptions.select_related("exercise").order_by("-start_date")
    return [adherence(p) for p in prescriptions]
