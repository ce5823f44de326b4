"""Progression of one patient: every analysed recording's headline figures, oldest first.

Used by the progress JSON endpoint, the charts, the reports and the REST API. One query reads the
patient's succeeded runs with their recordings and each run's stored progress point (a small
row rendered when the run succeeded, `webapp.patients.progress_store`), never the runs' 10–20 kB
summaries: at thousands of runs per patient, extracting from every summary and encoding every
point again was most of the endpoints' time. A run without a stored point (written before the
store existed) gets one on the way, in two more queries.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from datetime import date, datetime, time, timedelta
from typing import Any

from django.db.models import Case, F, Q, TextField, When
from django.utils.timezone import localtime

from analysis.clinical.labels import REGIONS, angle_label, region_of
from analysis.clinical.norms import norm_for
from webapp.api.numbers import utc_iso
from webapp.patients.models import Patient
from webapp.patients.progress_store import store_points
from webapp.recordings.models import AnalysisRun, RunStatus
from webapp.recordings.words import body_part

# What may change after a run (the exercise's name, the pain score) is read from the recording.
POINT_FIELDS = (
    "pk",
    "recording_id",
    "recording__exercise_id",
    "recording__exercise__name",
    "recording__uploaded_at",
    "recording__pain_score",
)
STORED = {
    "page": F("progress_point__page"),
    "api": F("progress_point__api"),
    # The page text of clinical points only (the clinical charts leave the others out).
    "clinical": Case(
        When(progress_point__clinical=True, then=F("progress_point__page")),
        default=None,
        output_field=TextField(),
    ),
}
RUN, RECORDING, EXERCISE, NAME, DATE, PAIN, TEXT, JOINTS, CLINICAL = range(9)


def latest_runs(
    patient: Patient, exercise_id: str | None = None, since=None, until=None, text: str = "page"
) -> list[tuple]:
    """Rows (POINT_FIELDS, the stored point's `text`, joints, clinical), one per recording with
    a succeeded run, by its newest succeeded run, ordered by upload. `text`: "page" (as
    `patient_progress` returns points), "api" (rounded), "clinical" (page, clinical points only).
    """
    runs = (
        AnalysisRun.objects.filter(
            recording__patient=patient,
            recording__deleted_at__isnull=True,
            status=RunStatus.SUCCEEDED,
        )
        # A recording moved to another exercise counts only by the runs of its new exercise.
        .filter(Q(model__isnull=True) | Q(model__exercise_id=F("recording__exercise_id")))
        .order_by("recording__uploaded_at", "created_at")
    )
    if exercise_id:
        runs = runs.filter(recording__exercise_id=exercise_id)
    if since:
        runs = runs.filter(recording__uploaded_at__date__gte=since)
    if until:
        runs = runs.filter(recording__uploaded_at__date__lte=until)
    latest: dict[Any, tuple] = {}
    columns = (STORED[text], "progress_point__joints", "progress_point__clinical")
    for row in runs.values_list(*POINT_FIELDS, *columns):
        latest[row[RECORDING]] = row  # a re-analysed recording counts once, by its newest run
    rows = list(latest.values())
    missing = [row[RUN] for row in rows if row[JOINTS] is None]  # no stored point
    if missing:
        stored = store_points(missing)
        rows = [row if row[JOINTS] is not None else _with_point(row, stored, text) for row in rows]
    return rows


def _with_point(row: tuple, stored: dict, text: str) -> tuple:
    point = stored[row[RUN]]
    clinical = point.page if point.clinical else None
    texts = {"page": point.page, "api": point.api, "clinical": clinical}
    return (*row[:TEXT], texts[text], point.joints, point.clinical)


def point_of(row: tuple) -> dict[str, Any]:
    figures = json.loads(row[TEXT])
    exercise = row[EXERCISE]
    return {
        "run": str(row[RUN]),
        "recording": str(row[RECORDING]),
        "exercise": str(exercise) if exercise else None,
        "exercise_name": row[NAME] if exercise else None,
        "date": localtime(row[DATE]).isoformat(),  # the clinic's day, as the pages show it
        "score": figures["score"],
        "repetitions": figures["repetitions"],
        "range_of_motion": figures["range_of_motion"],
        "gamma": figures["gamma"],
        "pain_score": row[PAIN],
        "clinical_angles": figures["clinical_angles"],
        "workspace": figures["workspace"],
    }


def patient_progress(
    patient: Patient, exercise_id: str | None = None, since=None, until=None
) -> list[dict[str, Any]]:
    return [point_of(row) for row in latest_runs(patient, exercise_id, since, until)]


def progress_points_json(
    patient: Patient, exercise_id: str | None = None, since=None, until=None, api: bool = False
) -> tuple[str, set[str]]:
    """The JSON text of `patient_progress`'s points (rounded and dated as the API answers them
    when `api`), joined from the stored texts without decoding them, and the body parts named in
    the points' range of motion and γ."""
    rows = latest_runs(patient, exercise_id, since, until, text="api" if api else "page")
    names: dict[Any, str] = {}
    joint_lists: set[str] = set()  # most runs of an exercise name the same body parts
    parts = []
    for row in rows:
        exercise = row[EXERCISE]
        if exercise not in names:
            names[exercise] = json.dumps(row[NAME] if exercise else None)
        joint_lists.add(row[JOINTS])
        date = utc_iso(row[DATE]) if api else localtime(row[DATE]).isoformat()
        head = (
            f'{{"run": "{row[RUN]}", "recording": "{row[RECORDING]}", "exercise": '
            f'{json.dumps(str(exercise)) if exercise else "null"}, "exercise_name": '
            f'{names[exercise]}, "date": "{date}", "pain_score": {json.dumps(row[PAIN])}, '
        )
        parts.append(head + row[TEXT][1:])
    joints = {joint for text in joint_lists for joint in json.loads(text)}
    return "[" + ", ".join(parts) + "]", joints


WORKSPACE_LABELS = {"left": "Left hand", "right": "Right hand"}
REGION_ORDER = {title: i for i, (title, _) in enumerate(REGIONS)}


def _exercise_series(points: list[dict[str, Any]]) -> dict[str, Any]:
    """One exercise's clinical series over its sessions (None where a session lacks a value)."""
    names = sorted(
        {n for p in points for n in p["clinical_angles"]},
        key=lambda n: (REGION_ORDER.get(region_of(n), len(REGION_ORDER)), n),
    )
    angles = [
        {
            "name": name,
            "label": angle_label(name),
            "region": region_of(name),
            "range": [p["clinical_angles"].get(name, {}).get("range") for p in points],
            "min": [p["clinical_angles"].get(name, {}).get("min") for p in points],
            "max": [p["clinical_angles"].get(name, {}).get("max") for p in points],
        }
        for name in names
    ]
    sides = sorted({s for p in points for s in p["workspace"]})
    workspace = [
        {
            "side": side,
            "label": WORKSPACE_LABELS.get(side, side),
            "percent": [_percent(p["workspace"].get(side)) for p in points],
        }
        for side in sides
    ]
    dates = [p["date"][:10] for p in points]
    moments = [datetime.fromisoformat(p["date"]) for p in points]
    shown = most_moved({a["name"]: a["range"] for a in angles})
    return {
        "dates": dates,
        **session_axis(moments),
        "angles": [{**a, "shown": a["name"] in shown} for a in angles],
        "band": normal_band(shown),
        "workspace": workspace,
    }


MAX_LINES = 4  # lines per chart: more and a chart no longer reads in a second
DAY_MS = 86_400_000
MAX_TICKS = 8


def most_moved(series: dict[str, list[float | None]], count: int = MAX_LINES) -> list[str]:
    """The names of the `count` series that reach the largest values (the angles or body parts
    the exercise moves most), largest first."""
    peak = {
        name: max((v for v in values if v is not None), default=-1.0)
        for name, values in series.items()
    }
    return sorted(peak, key=lambda name: (-peak[name], name))[:count]


def session_x(moments: list[datetime]) -> list[str]:
    """Where each session sits on a date axis: within its day, the sessions of that day spread
    evenly (k-th of n at (k+1)/(n+1) of the day), so same-day sessions stand side by side
    instead of on one vertical line."""
    per_day = Counter(m.date() for m in moments)
    seen: Counter = Counter()
    placed = []
    for moment in moments:
        day = moment.date()
        seen[day] += 1
        offset = timedelta(days=seen[day] / (per_day[day] + 1))
        placed.append(_stamp(datetime.combine(day, time.min) + offset))
    return placed


def date_axis(days: list[date]) -> dict[str, Any]:
    """A date axis from the first to the last day with a margin: ticks on whole days, labelled
    "12 Nov", at most MAX_TICKS of them, so one session never gives sub-second ticks."""
    first, last = (min(days), max(days)) if days else (date.today(), date.today())
    step = max(1, math.ceil(((last - first).days + 1) / MAX_TICKS))
    start = datetime.combine(first, time.min) - timedelta(hours=6)  # no tick of the day before
    end = datetime.combine(last, time.min) + timedelta(hours=30)
    return {
        "range": [_stamp(start), _stamp(end)],
        "tick0": _stamp(datetime.combine(first, time(12))),
        "dtick": step * DAY_MS,
        "tickformat": "%-d %b",
    }


def session_axis(moments: list[datetime]) -> dict[str, Any]:
    """The x of each session, its date and time in words (for the tooltip) and the date axis."""
    return {
        "x": session_x(moments),
        "when": [f"{m:%-d %b %Y %H:%M}" for m in moments],
        "axis": date_axis([m.date() for m in moments]),
    }


def _stamp(moment: datetime) -> str:
    return moment.strftime("%Y-%m-%d %H:%M:%S")


def normal_band(names: list[str]) -> dict[str, Any] | None:
    """The normal adult range of motion (AAOS) of the angles shown, as a band from the smallest
    to the largest of their full ranges (at least 4° tall, so one angle still shows)."""
    ranges = []
    for name in names:
        try:
            ranges.append(norm_for(name).range)
        except KeyError:  # not a clinical angle: no published norm
            continue
    if not ranges:
        return None
    low, high = min(ranges), max(ranges)
    if high - low < 4:
        low, high = (low + high) / 2 - 2, (low + high) / 2 + 2
    least, most = min(ranges), max(ranges)
    figures = f"{least:g}°" if least == most else f"{least:g}–{most:g}°"
    return {"low": low, "high": high, "text": f"normal adult range {figures}"}


def angle_line_label(name: str) -> str:
    """A clinical angle with its normal adult range: "Left knee flexion (normal 0° to 135°)"."""
    try:
        norm = norm_for(name)
    except KeyError:  # no published norm
        return angle_label(name)
    return f"{angle_label(name)} (normal {norm.minimum:g}° to {norm.maximum:g}°)"


def exercise_charts(name: str, points: list[dict[str, Any]]) -> dict[str, Any]:
    """One exercise's progress charts: one point per session placed by date, the score, the
    repetitions, the pain, the range of the (up to) MAX_LINES clinical angles the exercise moves
    most (the same ranges as the recording's table of angles, by name with their normal range)
    and the level of the MAX_LINES body parts the analysis compares most."""
    angles = {
        n: [(p["clinical_angles"].get(n) or {}).get("range") for p in points]
        for p in points
        for n in p["clinical_angles"]
    }
    rom = {
        j: [p["range_of_motion"].get(j) for p in points]
        for p in points
        for j in p["range_of_motion"]
    }
    return {
        "exercise": name,
        **session_axis([datetime.fromisoformat(p["date"]) for p in points]),
        "score": [p["score"] for p in points],
        "repetitions": [p["repetitions"] for p in points],
        "pain": [p["pain_score"] for p in points],
        "rom": [
            {"name": n, "label": angle_line_label(n), "y": angles[n]} for n in most_moved(angles)
        ],
        "gamma": [
            {"label": body_part(j).capitalize(), "y": [p["gamma"].get(j) for p in points]}
            for j in most_moved(rom)
        ],
    }


def progress_charts(patient: Patient) -> list[dict[str, Any]]:
    """Per exercise (sessions of different exercises are never joined), `exercise_charts`; the
    exercise with the most sessions first."""
    by_exercise: dict[str, list[dict[str, Any]]] = {}
    for point in patient_progress(patient):
        by_exercise.setdefault(point["exercise_name"] or "Unknown exercise", []).append(point)
    ordered = sorted(by_exercise.items(), key=lambda item: -len(item[1]))
    return [
        {"id": f"progress-{i}", **exercise_charts(name, points)}
        for i, (name, points) in enumerate(ordered)
    ]


def _percent(share: float | None) -> float | None:
    return None if share is None else round(100.0 * share, 1)


def clinical_progress(patient: Patient) -> list[dict[str, Any]]:
    """Per exercise (never mixing exercises in one series), each clinical angle's range in
    degrees and each hand's reachable area (% of the front hemisphere) over the session dates.
    One query (`latest_runs`); sessions without clinical measures are left out, undecoded."""
    by_exercise: dict[str, list[dict[str, Any]]] = {}
    for row in latest_runs(patient, text="clinical"):
        if row[CLINICAL]:
            point = point_of(row)
            by_exercise.setdefault(point["exercise_name"] or "Unknown exercise", []).append(point)
    return [
        {"exercise": name, "id": f"clinical-{i}", **_exercise_series(points)}
        for i, (name, points) in enumerate(by_exercise.items())
    ]
