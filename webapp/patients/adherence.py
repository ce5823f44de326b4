"""Adherence: sessions done versus sessions prescribed, per prescription, and days with data.

A session is a day (in the site's time zone) with at least one recording of the exercise by the
patient within the prescription's dates: several uploads on one day count once, as the patient
exercised once. Three figures:

- Since the start: `sessions_per_week` × the weeks (fractional, rounded up) the prescription has
  been active up to today (or its end date), against the days with a session in that time.
- The last 4 weeks (`last_4_weeks`): the 28 days ending today, taken as four weeks of seven days
  (the newest ends today). Each week prescribes `sessions_per_week` × its active days / 7
  sessions (rounded up) and counts at most that many done: extra sessions in one week do not
  make up for a missed week. Its percent is the sessions counted over the sessions prescribed.
- Days with data in the last 30 days (`DaysWithData`): distinct days, today and the 29 before,
  with at least one recording of any exercise, the count remote-monitoring reimbursement asks
  for (16 of 30 days for the US code CPT 99454, for example).
"""

from __future__ import annotations

import datetime
import math
from collections import defaultdict
from collections.abc import Iterable
from dataclasses import asdict, dataclass
from typing import Any, Protocol

from django.db.models.functions import TruncDate
from django.utils import timezone

from webapp.patients.models import Prescription
from webapp.recordings.models import Recording

RECENT_WEEKS = 4
DATA_WINDOW_DAYS = 30
WEEK = datetime.timedelta(days=7)


class PrescribedPeriod(Protocol):
    """What counting prescribed sessions needs: a `Prescription`, or a period built from one."""

    @property
    def start_date(self) -> datetime.date: ...

    @property
    def end_date(self) -> datetime.date | None: ...

    @property
    def sessions_per_week(self) -> int | None: ...


@dataclass(frozen=True)
class WeekAdherence:
    first: datetime.date
    last: datetime.date
    sessions_prescribed: int
    sessions_done: int


@dataclass(frozen=True)
class RecentAdherence:
    """The last `RECENT_WEEKS` weeks, oldest week first."""

    first: datetime.date
    last: datetime.date
    sessions_prescribed: int
    sessions_done: int  # each week counts at most the sessions it prescribes
    percent: float | None  # None when nothing was prescribed in these weeks
    weeks: tuple[WeekAdherence, ...]


@dataclass(frozen=True)
class Adherence:
    prescription: str
    exercise: str
    exercise_name: str
    sessions_prescribed: int
    sessions_done: int
    percent: float | None  # None before the first prescribed session is due
    last_4_weeks: RecentAdherence

    def to_json(self) -> dict[str, Any]:
        return dates_as_text(asdict(self))


@dataclass(frozen=True)
class DaysWithData:
    first: datetime.date
    last: datetime.date
    days: int
    window_days: int = DATA_WINDOW_DAYS

    def to_json(self) -> dict[str, Any]:
        return dates_as_text(asdict(self))


def dates_as_text(value: Any) -> Any:
    if isinstance(value, dict):
        return {key: dates_as_text(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [dates_as_text(item) for item in value]
    return value.isoformat() if isinstance(value, datetime.date) else value


def percent(done: int, expected: int) -> float | None:
    return round(100.0 * min(done, expected) / expected, 1) if expected else None


def prescribed_between(
    prescription: PrescribedPeriod, first: datetime.date, last: datetime.date
) -> int:
    """Sessions prescribed on the days `first`..`last` within the prescription's dates."""
    start = max(first, prescription.start_date)
    end = min(last, prescription.end_date) if prescription.end_date else last
    days = (end - start).days + 1
    if days <= 0 or not prescription.sessions_per_week:
        return 0
    return math.ceil(prescription.sessions_per_week * days / 7)


def prescribed_sessions(prescription: PrescribedPeriod, today: datetime.date) -> int:
    return prescribed_between(prescription, prescription.start_date, today)


def session_days(
    patient_id: Any, since: datetime.date | None = None
) -> dict[Any, set[datetime.date]]:
    """The days with a recording, per exercise id (None: recordings whose exercise is not
    confirmed yet), in one query."""
    recordings = Recording.objects.filter(patient_id=patient_id)
    if since is not None:
        recordings = recordings.filter(uploaded_at__date__gte=since)
    rows = (
        recordings.annotate(day=TruncDate("uploaded_at"))
        .values_list("exercise_id", "day")
        .order_by()
        .distinct()
    )
    days: dict[Any, set[datetime.date]] = defaultdict(set)
    for exercise_id, day in rows:
        days[exercise_id].add(day)
    return days


def count_between(days: Iterable[datetime.date], first: datetime.date, last: datetime.date) -> int:
    return sum(1 for day in days if first <= day <= last)


def recent_adherence(
    prescription: PrescribedPeriod, days: set[datetime.date], today: datetime.date
) -> RecentAdherence:
    """Adherence over the last four weeks; `days` are the prescription's session days."""
    weeks = []
    for back in reversed(range(RECENT_WEEKS)):
        last = today - back * WEEK
        first = last - datetime.timedelta(days=6)
        expected = prescribed_between(prescription, first, last)
        weeks.append(WeekAdherence(first, last, expected, count_between(days, first, last)))
    expected = sum(w.sessions_prescribed for w in weeks)
    counted = sum(min(w.sessions_done, w.sessions_prescribed) for w in weeks)
    return RecentAdherence(
        weeks[0].first, today, expected, counted, percent(counted, expected), tuple(weeks)
    )


def adherence(
    prescription: Prescription,
    today: datetime.date | None = None,
    days: set[datetime.date] | None = None,
) -> Adherence:
    """`days`: the patient's days with a recording of the exercise (read when not given)."""
    today = today or timezone.localdate()
    if days is None:
        found = session_days(prescription.patient_id, since=prescription.start_date)
        days = found.get(prescription.exercise_id, set())
    end = min(today, prescription.end_date) if prescription.end_date else today
    active = {day for day in days if prescription.start_date <= day <= end}
    expected = prescribed_sessions(prescription, today)
    return Adherence(
        prescription=str(prescription.pk),
        exercise=str(prescription.exercise_id),
        exercise_name=prescription.exercise.name,
        sessions_prescribed=expected,
        sessions_done=len(active),
        percent=percent(len(active), expected),
        last_4_weeks=recent_adherence(prescription, active, today),
    )


def days_with_data(
    days: dict[Any, set[datetime.date]], today: datetime.date | None = None
) -> DaysWithData:
    """Days with at least one recording of any exercise in the `DATA_WINDOW_DAYS` ending today."""
    today = today or timezone.localdate()
    first = today - datetime.timedelta(days=DATA_WINDOW_DAYS - 1)
    every_day = set().union(*days.values()) if days else set()
    return DaysWithData(first, today, count_between(every_day, first, today))


def patient_adherence(
    patient, today: datetime.date | None = None, prescriptions: Iterable[Prescription] | None = None
) -> tuple[list[Adherence], DaysWithData]:
    """Each prescription's adherence (newest first unless `prescriptions` are given) and the
    patient's days with data, from one query of recordings."""
    today = today or timezone.localdate()
    if prescriptions is None:
        prescriptions = patient.prescriptions.select_related("exercise").order_by("-start_date")
    prescriptions = list(prescriptions)
    since = min([p.start_date for p in prescriptions], default=today)
    since = min(since, today - datetime.timedelta(days=DATA_WINDOW_DAYS - 1))
    days = session_days(patient.pk, since=since)
    found = [adherence(p, today, days.get(p.exercise_id, set())) for p in prescriptions]
    return found, days_with_data(days, today)
