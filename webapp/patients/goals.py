"""Goals per patient and exercise: what they measure, how they read, how they are judged.

A goal (`webapp.patients.models.Goal`) asks a patient to reach a target by a date, for one
exercise: a clinical angle's range of motion (degrees, `analysis.clinical.ANGLE_NAMES`), the
session score (0–100) or adherence (% of the prescribed sessions done over the last four weeks).
Every measure is one where more is better, so a goal reads "reach 90°" and is met once the
latest value is at least the target.

Values come from the patient's analysed sessions of the goal's exercise, oldest first (the same
stored progress points as the charts, `webapp.patients.progress`), or for adherence from the
exercise's newest prescription (`webapp.patients.adherence`). A goal is:

- met: the latest value reaches the target;
- not met: its date has passed and the latest value does not reach the target (or there is none);
- off track: before its date, the latest value is further from the target than the first one
  (a deliberately simple rule: the patient has gone backwards since the series began; the
  adherence figure has no series, so an adherence goal is only ever judged by its date);
- on track: otherwise, with at least one value; no data yet: without any.

Not met and off track goals give an attention entry on the home page (`off_track_reasons`).
"""

from __future__ import annotations

import datetime
import json
import math
from collections import defaultdict
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from django.db.models import F, Q
from django.utils import timezone
from django.utils.dateformat import format as format_date

from analysis.clinical import ANGLE_NAMES
from analysis.clinical.labels import angle_label
from analysis.clinical.norms import limits_for
from webapp.patients.models import Goal, Patient
from webapp.patients.progress_store import store_points
from webapp.recordings.models import AnalysisRun, RunStatus

SCORE, ADHERENCE = "score", "adherence"
MEASURES: tuple[str, ...] = (SCORE, ADHERENCE, *ANGLE_NAMES)
# Lowest and highest target of each kind of measure (angles in degrees, the others in %).
TARGET_LIMITS = {SCORE: (0.0, 100.0), ADHERENCE: (0.0, 100.0), "angle": (-180.0, 360.0)}
MET, NOT_MET, OFF_TRACK, ON_TRACK, NO_DATA = "met", "not met", "off track", "on track", "no data"
FINITE = "The target must be a finite number."
STATE_WORDS = {
    MET: "met",
    NOT_MET: "not met by the date",
    OFF_TRACK: "off track",
    ON_TRACK: "on track",
    NO_DATA: "no sessions yet",
}


def measure_error(measure: str) -> str:
    """A plain message when `measure` is not one a goal can have ("" when it is)."""
    if measure in MEASURES:
        return ""
    return f"Unknown measure '{measure}'. Accepted measures: {', '.join(MEASURES)}."


def target_error(measure: str, target: float) -> str:
    """A plain message when the target is not a finite number in the measure's range."""
    if not math.isfinite(target):
        return FINITE
    if measure not in (SCORE, ADHERENCE):
        return angle_target_error(measure, target)
    low, high = TARGET_LIMITS[measure]
    if not low <= target <= high:
        return f"The target must be between {low:g} and {high:g} {unit_of(measure)}."
    return ""


def angle_target_error(measure: str, target: float) -> str:
    """An angle's target is a range of motion: from 0 to the most a body can move that joint
    (its physiological limits, `analysis.clinical.norms.LIMITS`), or "" when it is within."""
    low, high = limits_for(measure)
    most = high - low
    if 0 <= target <= most:
        return ""
    return (
        f"A {measure_label(measure).lower()} target must be between 0 and {most:g}° of range of "
        f"motion: no body moves that joint further ({low:g}° to {high:g}°)."
    )


def unit_of(measure: str) -> str:
    return "points (0–100)" if measure == SCORE else "%" if measure == ADHERENCE else "degrees"


def measure_label(measure: str) -> str:
    """The measure in plain words: "Score", "Adherence", "Left knee flexion"."""
    if measure == SCORE:
        return "Score"
    if measure == ADHERENCE:
        return "Adherence"
    return angle_label(measure)


def target_words(measure: str, target: float) -> str:
    if measure == SCORE:
        return f"a score of {target:g} / 100"
    if measure == ADHERENCE:
        return f"{target:g} % of the prescribed sessions"
    return f"{target:g}° range of motion"


def goal_words(goal: Goal) -> str:
    """ "Left knee flexion: reach 90° range of motion by 12 March 2027"."""
    by = format_date(goal.by, "j F Y")
    return f"{measure_label(goal.measure)}: reach {target_words(goal.measure, goal.target)} by {by}"


@dataclass(frozen=True)
class GoalStatus:
    goal: Goal
    words: str
    first: float | None
    latest: float | None
    state: str

    @property
    def state_words(self) -> str:
        return STATE_WORDS[self.state]

    @property
    def needs_attention(self) -> bool:
        return self.state in (NOT_MET, OFF_TRACK)

    def latest_words(self) -> str:
        if self.latest is None:
            return "no value yet"
        unit = "°" if self.goal.measure not in (SCORE, ADHERENCE) else ""
        unit = " %" if self.goal.measure == ADHERENCE else unit
        return f"{self.latest:.0f}{unit}"


def judge(goal: Goal, values: list[float], today: datetime.date) -> str:
    """The goal's state from its values, oldest first (see the module's docstring)."""
    latest = values[-1] if values else None
    if latest is not None and latest >= goal.target:
        return MET
    if goal.by < today:
        return NOT_MET
    if latest is None:
        return NO_DATA
    further = goal.target - latest > goal.target - values[0]  # below target, and lower than first
    return OFF_TRACK if further else ON_TRACK


def value_of(figures: dict[str, Any], measure: str) -> float | None:
    """A session's value of `measure` from its progress point's figures."""
    if measure == SCORE:
        return figures.get("score")
    angle = (figures.get("clinical_angles") or {}).get(measure)
    return angle.get("range") if isinstance(angle, dict) else None


def session_figures(pairs: set[tuple[Any, Any]]) -> dict[tuple[Any, Any], list[dict[str, Any]]]:
    """Per (patient id, exercise id), each analysed recording's figures, oldest first: one query
    over all the pairs (their recordings' newest succeeded runs' stored progress points)."""
    if not pairs:
        return {}
    runs = (
        AnalysisRun.objects.filter(
            status=RunStatus.SUCCEEDED,
            recording__deleted_at__isnull=True,
            recording__patient_id__in={p for p, _ in pairs},
            recording__exercise_id__in={e for _, e in pairs},
        )
        # As the charts: a moved recording counts only by the runs of its new exercise.
        .filter(Q(model__isnull=True) | Q(model__exercise_id=F("recording__exercise_id")))
        .order_by("recording__uploaded_at", "created_at")
        .values_list(
            "pk", "recording_id", "recording__patient_id", "recording__exercise_id",
            "progress_point__page",
        )
    )  # fmt: skip
    newest: dict[Any, tuple] = {}
    for row in runs:
        if (row[2], row[3]) in pairs:
            newest[row[1]] = row  # a re-analysed recording counts once, by its newest run
    missing = [row[0] for row in newest.values() if row[4] is None]
    stored = store_points(missing) if missing else {}
    found: dict[tuple[Any, Any], list[dict[str, Any]]] = defaultdict(list)
    for run_id, _, patient_id, exercise_id, page in newest.values():
        text = page if page is not None else stored[run_id].page
        found[(patient_id, exercise_id)].append(json.loads(text))
    return found


def adherence_percents(patient: Patient) -> dict[Any, float | None]:
    """Per exercise id, the last four weeks' adherence of its newest prescription."""
    from webapp.patients.adherence import patient_adherence  # reads recordings: only when asked

    prescriptions = patient.prescriptions.select_related("exercise").order_by("start_date")
    found, _ = patient_adherence(patient, prescriptions=prescriptions)
    return {figures.exercise: figures.last_4_weeks.percent for figures in found}


def statuses(goals: Iterable[Goal], today: datetime.date | None = None) -> list[GoalStatus]:
    """Each goal with its first and latest value and its state (goals of any patients)."""
    goals = list(goals)
    today = today or timezone.localdate()
    figures = session_figures(
        {(g.patient_id, g.exercise_id) for g in goals if g.measure != ADHERENCE}
    )
    adherence: dict[Any, dict[Any, float | None]] = {}
    found = []
    for goal in goals:
        if goal.measure == ADHERENCE:
            if goal.patient_id not in adherence:
                adherence[goal.patient_id] = adherence_percents(goal.patient)
            percent = adherence[goal.patient_id].get(str(goal.exercise_id))
            values = [] if percent is None else [percent]
        else:
            points = figures.get((goal.patient_id, goal.exercise_id), [])
            values = [v for v in (value_of(p, goal.measure) for p in points) if v is not None]
        first, latest = (values[0], values[-1]) if values else (None, None)
        found.append(GoalStatus(goal, goal_words(goal), first, latest, judge(goal, values, today)))
    return found


def patient_goal_statuses(patient: Patient) -> list[GoalStatus]:
    return statuses(patient.goals.select_related("exercise", "patient"))


def attention_text(status: GoalStatus) -> str:
    now = status.latest_words()
    if status.state == NOT_MET:
        return f"{status.goal.exercise.name}: goal not met by its date ({status.words}; now {now})"
    return (
        f"{status.goal.exercise.name}: goal off track ({status.words}; now {now}, "
        "lower than at the start)"
    )


def off_track_goals(
    clinic_id: Any, today: datetime.date, patient_id: Any = None
) -> list[GoalStatus]:
    """The clinic's goals that are not met by their date or off track (patients under
    treatment only)."""
    goals = Goal.objects.filter(
        patient__clinic_id=clinic_id,
        patient__archived_at__isnull=True,
        patient__deleted_at__isnull=True,
    ).select_related("exercise", "patient")
    if patient_id is not None:
        goals = goals.filter(patient_id=patient_id)
    return [s for s in statuses(goals, today) if s.needs_attention]


def chart_lines(patient: Patient) -> list[dict[str, Any]]:
    """The score and angle goals as the progress charts draw them (a dashed line at the target
    up to the goal's date, labelled "goal" with its unit); adherence goals have no such chart."""
    lines = []
    for goal in patient.goals.select_related("exercise"):
        if goal.measure == ADHERENCE:
            continue
        unit = " points" if goal.measure == SCORE else "°"
        lines.append(
            {
                "exercise": goal.exercise.name,
                "chart": "score" if goal.measure == SCORE else "angle",
                "label": measure_label(goal.measure),
                "target": goal.target,
                "by": goal.by.isoformat(),
                "text": f"goal {goal.target:g}{unit}",
            }
        )
    return lines
