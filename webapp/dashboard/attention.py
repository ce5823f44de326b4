"""Which of a clinic's patients need a therapist's attention, and why.

Five signals, each one query over the clinic (never one query per patient):

- a failed analysis: the newest run of a recent recording failed (the patient or the file may
  need help before the next session);
- falling scores: the newest score of an exercise is well below the mean of the (up to three)
  scores before it; a window function picks the newest four runs per patient and exercise,
  the comparison is made here;
- missed sessions: fewer than half the sessions a prescription asks for were done over the last
  two weeks (sessions counted as in `webapp.patients.adherence`: days with a recording);
- pain: a recording of the last two weeks came with a pain score of PAIN_ATTENTION (6/10) or
  more (the newest such recording per patient), or pain rising over the last PAIN_TREND_SESSIONS
  sessions with a pain score (never falling between two of them, up PAIN_RISE points or more);
- goals: a goal not met by its date, or off track (`webapp.patients.goals` says when), read in
  one query over the clinic's goals and one over their sessions (plus the adherence of the
  patients with an adherence goal).

Archived and deleted patients are left out: nobody is treating them.

Cost: the falling-score query reads the runs of the last TREND_WITHIN_DAYS days; it takes their
numeric `score` column (a copy of the summary's score), never the 10–20 kB summaries.
"""

from __future__ import annotations

import datetime
from dataclasses import dataclass, field
from itertools import pairwise
from typing import Any, NamedTuple

from django.db.models import (
    Count,
    Exists,
    F,
    Max,
    OuterRef,
    Q,
    QuerySet,
    Window,
)
from django.db.models.functions import RowNumber, TruncDate
from django.utils import timezone

from webapp.patients.adherence import prescribed_sessions
from webapp.patients.goals import NOT_MET, attention_text, off_track_goals
from webapp.patients.models import Prescription
from webapp.recordings.models import AnalysisRun, Recording, RunStatus

FAILED_WITHIN_DAYS = 14
TREND_WITHIN_DAYS = 45  # scores older than this do not count toward a trend (nor get read)
TREND_LATEST_WITHIN_DAYS = 30  # the falling score itself must be this recent
TREND_EARLIER_RUNS = 3
SCORE_DROP = 10.0  # points (scores are 0–100)
ADHERENCE_WINDOW_DAYS = 14
ADHERENCE_MIN_PERCENT = 50.0
NEWEST_FIRST = (F("recording__uploaded_at").desc(), F("created_at").desc())
PAIN_ATTENTION = 6  # of 10: from here on a therapist looks before the next session
PAIN_WITHIN_DAYS = 14
PAIN_TREND_SESSIONS = 3  # the newest sessions with a pain score, read as a trend
PAIN_RISE = 2  # points of 10 from the first to the last of them
ROWS_PER_SIGNAL = 500  # caps each query; a clinic with more flags has bigger problems
GOAL_URGENCY = {NOT_MET: 150.0}  # below missed sessions and falling scores; off track: 120


@dataclass(frozen=True)
class Reason:
    kind: str  # "failed" | "falling" | "adherence" | "pain" | "goal"
    text: str
    urgency: float  # higher first
    recording_id: Any = None  # the recording to open, when there is one


@dataclass
class Attention:
    patient_id: Any
    reasons: list[Reason] = field(default_factory=list)
    patient: Any = None  # filled for the patients shown

    @property
    def urgency(self) -> float:
        return max(r.urgency for r in self.reasons) + 0.01 * len(self.reasons)


class Period(NamedTuple):
    """What `prescribed_sessions` reads of a prescription, clipped to the adherence window."""

    start_date: datetime.date
    end_date: datetime.date | None
    sessions_per_week: int


def clinic_runs(clinic_id: Any, patient_id: Any = None) -> QuerySet[AnalysisRun]:
    runs = AnalysisRun.objects.filter(
        recording__clinic_id=clinic_id,
        recording__deleted_at__isnull=True,
        recording__patient__deleted_at__isnull=True,
        recording__patient__archived_at__isnull=True,
    )
    return runs if patient_id is None else runs.filter(recording__patient_id=patient_id)


def failed_analyses(
    clinic_id: Any, now: datetime.datetime, patient_id: Any = None
) -> list[tuple[Any, Reason]]:
    newer = AnalysisRun.objects.filter(
        recording_id=OuterRef("recording_id"), created_at__gt=OuterRef("created_at")
    )
    rows = (
        clinic_runs(clinic_id, patient_id)
        .filter(status=RunStatus.FAILED, created_at__gte=now - _days(FAILED_WITHIN_DAYS))
        .filter(~Exists(newer))
        .order_by("-created_at")
        .values("recording_id", "recording__patient_id", "recording__exercise__name")
    )
    found = []
    for row in rows[:ROWS_PER_SIGNAL]:
        exercise = row["recording__exercise__name"] or "a recording"
        reason = Reason("failed", f"Analysis of {exercise} failed", 300.0, row["recording_id"])
        found.append((row["recording__patient_id"], reason))
    return found


def recent_scores(
    clinic_id: Any, now: datetime.datetime, patient_id: Any = None
) -> QuerySet[AnalysisRun]:
    """The newest few scores per (patient, exercise), for pairs whose newest run is recent.

    Rows come newest first within each pair (`position` 1 is the newest).
    """
    pair = [F("recording__patient_id"), F("recording__exercise_id")]
    newer_success = AnalysisRun.objects.filter(
        recording_id=OuterRef("recording_id"),
        status=RunStatus.SUCCEEDED,
        created_at__gt=OuterRef("created_at"),
    )
    return (
        clinic_runs(clinic_id, patient_id)
        .filter(status=RunStatus.SUCCEEDED, recording__exercise__isnull=False)
        .filter(recording__uploaded_at__gte=now - _days(TREND_WITHIN_DAYS))
        .filter(~Exists(newer_success))  # a re-analysed recording counts once, by its newest run
        .annotate(
            position=Window(RowNumber(), partition_by=pair, order_by=NEWEST_FIRST),
            newest_at=Window(Max("recording__uploaded_at"), partition_by=pair),
        )
        .filter(position__lte=TREND_EARLIER_RUNS + 1)
        .filter(newest_at__gte=now - _days(TREND_LATEST_WITHIN_DAYS))
        .values(
            "recording_id",
            "recording__patient_id",
            "recording__exercise__name",
            "position",
            "score",
        )
        .order_by("recording__patient_id", "recording__exercise_id", "position")
    )


def falling_scores(
    clinic_id: Any, now: datetime.datetime, patient_id: Any = None
) -> list[tuple[Any, Reason]]:
    found: list[tuple[Any, Reason]] = []
    newest: dict | None = None
    earlier: list[float] = []
    for row in recent_scores(clinic_id, now, patient_id).iterator(chunk_size=5000):
        if row["position"] == 1:
            found += falling(newest, earlier)
            newest, earlier = row, []
        elif row["score"] is not None:
            earlier.append(row["score"])
    return (found + falling(newest, earlier))[:ROWS_PER_SIGNAL]


def falling(newest: dict | None, earlier: list[float]) -> list[tuple[Any, Reason]]:
    """The reason, when the newest score is SCORE_DROP below the mean of at least two before it."""
    if newest is None or newest["score"] is None or len(earlier) < 2:
        return []
    mean = sum(earlier) / len(earlier)
    drop = mean - newest["score"]
    if drop < SCORE_DROP:
        return []
    text = (
        f"{newest['recording__exercise__name']}: score {newest['score']:.0f}, "
        f"down {drop:.0f} from {mean:.0f}"
    )
    reason = Reason("falling", text, 200.0 + drop, newest["recording_id"])
    return [(newest["recording__patient_id"], reason)]


def missed_sessions(
    clinic_id: Any, today: datetime.date, patient_id: Any = None
) -> list[tuple[Any, Reason]]:
    window_start = today - _days(ADHERENCE_WINDOW_DAYS - 1)
    prescriptions = (
        Prescription.objects.filter(
            patient__clinic_id=clinic_id,
            patient__archived_at__isnull=True,
            patient__deleted_at__isnull=True,
            start_date__lte=today,
        )
        .filter(Q(end_date__isnull=True) | Q(end_date__gte=window_start))
        .values(
            "patient_id",
            "exercise_id",
            "exercise__name",
            "sessions_per_week",
            "start_date",
            "end_date",
        )
    )
    if patient_id is not None:
        prescriptions = prescriptions.filter(patient_id=patient_id)
    done = session_days(clinic_id, window_start, today, patient_id=patient_id)
    found = []
    for row in prescriptions.iterator(chunk_size=2000):
        period = Period(
            max(row["start_date"], window_start), row["end_date"], row["sessions_per_week"]
        )
        expected = prescribed_sessions(period, today)
        count = done.get((row["patient_id"], row["exercise_id"]), 0)
        if expected < 2 or 100.0 * count / expected >= ADHERENCE_MIN_PERCENT:
            continue
        text = (
            f"{row['exercise__name']}: {count} of {expected} prescribed sessions "
            f"in the last {ADHERENCE_WINDOW_DAYS} days"
        )
        found.append((row["patient_id"], Reason("adherence", text, 200.0 * (1 - count / expected))))
    return found


def reported_pain(
    clinic_id: Any, now: datetime.datetime, patient_id: Any = None
) -> list[tuple[Any, Reason]]:
    """The newest recording per patient of the last PAIN_WITHIN_DAYS days with a pain score of
    PAIN_ATTENTION or more; the worse the pain, the more urgent (between falling and failed)."""
    recordings = Recording.objects.filter(
        clinic_id=clinic_id,
        patient__archived_at__isnull=True,
        pain_score__gte=PAIN_ATTENTION,
        uploaded_at__gte=now - _days(PAIN_WITHIN_DAYS),
    )
    if patient_id is not None:
        recordings = recordings.filter(patient_id=patient_id)
    rows = recordings.order_by("-uploaded_at").values(
        "pk", "patient_id", "pain_score", "exercise__name", "uploaded_at"
    )
    found: dict[Any, Reason] = {}
    for row in rows[:ROWS_PER_SIGNAL]:
        if row["patient_id"] in found:
            continue  # the newest painful session speaks for the patient
        day = timezone.localtime(row["uploaded_at"]).strftime("%-d %b")
        exercise = row["exercise__name"] or "a session"
        text = f"{exercise}: pain {row['pain_score']}/10 reported on {day}"
        found[row["patient_id"]] = Reason("pain", text, 250.0 + 5 * row["pain_score"], row["pk"])
    return list(found.items())


def rising_pain(
    clinic_id: Any, now: datetime.datetime, patient_id: Any = None
) -> list[tuple[Any, Reason]]:
    """Patients whose pain score rose over their last PAIN_TREND_SESSIONS scored sessions (the
    newest of them in the last PAIN_WITHIN_DAYS days): a window function numbers each patient's
    scored recordings, newest first, and the rule is applied here."""
    recordings = Recording.objects.filter(
        clinic_id=clinic_id,
        deleted_at__isnull=True,
        patient__archived_at__isnull=True,
        patient__deleted_at__isnull=True,
        pain_score__isnull=False,
    )
    if patient_id is not None:
        recordings = recordings.filter(patient_id=patient_id)
    rows = (
        recordings.annotate(
            position=Window(
                RowNumber(), partition_by=[F("patient_id")], order_by=F("uploaded_at").desc()
            ),
            newest_at=Window(Max("uploaded_at"), partition_by=[F("patient_id")]),
        )
        .filter(position__lte=PAIN_TREND_SESSIONS, newest_at__gte=now - _days(PAIN_WITHIN_DAYS))
        .values("pk", "patient_id", "pain_score", "position")
        .order_by("patient_id", "-position")
    )
    by_patient: dict[Any, list[dict]] = {}
    for row in rows[: ROWS_PER_SIGNAL * PAIN_TREND_SESSIONS]:
        by_patient.setdefault(row["patient_id"], []).append(row)
    found = []
    for flagged, sessions in by_patient.items():
        reason = pain_trend([s["pain_score"] for s in sessions], sessions[-1]["pk"])
        if reason is not None:
            found.append((flagged, reason))
    return found


def pain_trend(scores: list[int], recording_id: Any = None) -> Reason | None:
    """The reason when pain scores (oldest first) never fall and rise PAIN_RISE points or more
    over PAIN_TREND_SESSIONS sessions; urgent as high pain, more so the steeper the rise."""
    if len(scores) < PAIN_TREND_SESSIONS:
        return None
    rise = scores[-1] - scores[0]
    if rise < PAIN_RISE or any(b < a for a, b in pairwise(scores)):
        return None
    text = f"Pain rising: {scores[0]} → {scores[-1]} (0–10) over the last {len(scores)} sessions"
    return Reason("pain", text, 250.0 + 5 * rise, recording_id)


def goals_off_track(
    clinic_id: Any, today: datetime.date, patient_id: Any = None
) -> list[tuple[Any, Reason]]:
    return [
        (
            status.goal.patient_id,
            Reason("goal", attention_text(status), GOAL_URGENCY.get(status.state, 120.0)),
        )
        for status in off_track_goals(clinic_id, today, patient_id)[:ROWS_PER_SIGNAL]
    ]


def session_days(
    clinic_id: Any, first: datetime.date, last: datetime.date, patient_id: Any = None
) -> dict[tuple[Any, Any], int]:
    """Days with at least one recording, per (patient, exercise), between two dates inclusive."""
    recordings = Recording.objects.filter(
        clinic_id=clinic_id,
        exercise__isnull=False,
        uploaded_at__gte=_start_of(first),
        uploaded_at__lt=_start_of(last + _days(1)),
    )
    if patient_id is not None:
        recordings = recordings.filter(patient_id=patient_id)
    rows = (
        recordings.values("patient_id", "exercise_id")
        .annotate(days=Count(TruncDate("uploaded_at"), distinct=True))
        .order_by()
    )
    return {(r["patient_id"], r["exercise_id"]): r["days"] for r in rows}


def patients_needing_attention(
    clinic_id: Any, now: datetime.datetime | None = None, patient_id: Any = None
) -> list[Attention]:
    """Patients with at least one reason, the most urgent first (seven queries in all, more
    for patients with an adherence goal).

    Computed from the runs, recordings and prescriptions; the home page reads the stored copy
    (`webapp.dashboard.precompute`). `patient_id`: that patient only (the update after a run).
    """
    if clinic_id is None:
        return []
    now = now or timezone.now()
    found = failed_analyses(clinic_id, now, patient_id)
    found += falling_scores(clinic_id, now, patient_id)
    found += missed_sessions(clinic_id, timezone.localdate(now), patient_id)
    found += reported_pain(clinic_id, now, patient_id)
    found += rising_pain(clinic_id, now, patient_id)
    found += goals_off_track(clinic_id, timezone.localdate(now), patient_id)
    by_patient: dict[Any, Attention] = {}
    for flagged, reason in found:
        by_patient.setdefault(flagged, Attention(flagged)).reasons.append(reason)
    for entry in by_patient.values():
        entry.reasons.sort(key=lambda r: -r.urgency)
    return sorted(by_patient.values(), key=lambda a: -a.urgency)


def _days(count: int) -> datetime.timedelta:
    return datetime.timedelta(days=count)


def _start_of(day: datetime.date) -> datetime.datetime:
    """Midnight of a local date, so that day ranges use the index on `uploaded_at`."""
    return timezone.make_aware(datetime.datetime.combine(day, datetime.time.min))
