"""What a report says, as plain data shared by the PDF and the printable HTML."""

from __future__ import annotations

from datetime import date, datetime
from typing import Any

from django.utils import timezone

from analysis.clinical.labels import angle_label
from webapp.patients.goals import patient_goal_statuses
from webapp.patients.progress import (
    MAX_LINES,
    angle_line_label,
    most_moved,
    patient_progress,
    session_x,
)
from webapp.recordings.notes import note_lines
from webapp.recordings.reading import reading_of
from webapp.recordings.words import body_part, key_pose_name
from webapp.reports import playback
from webapp.reports.clinical import clinical_content
from webapp.reports.timeline import timeline

MAX_POSES = 4
MAX_ROM_LINES = MAX_LINES  # angles per exercise chart: the ones the exercise moves most


def fmt(value: Any, digits: int = 0) -> str:
    return "–" if value is None else f"{float(value):.{digits}f}"


def key_poses(run) -> tuple[list, list[int]]:
    try:
        arrays = playback.load_arrays(run)
    except (OSError, ValueError, KeyError):
        return [], []
    positions = arrays["patient_positions"]
    kinds = playback.type_names(run)
    fps = float(run.result.fps or run.recording.fps or 30.0)
    poses = []
    for mark in run.result.landmarks[:MAX_POSES]:
        frame = min(mark.frame, positions.shape[0] - 1)
        name = key_pose_name(mark.type, kinds)
        poses.append((f"{name} · {frame / fps:.1f} s", positions[frame]))
    return poses, [int(p) for p in arrays["parents"]]


def guidance_text(rep: dict[str, Any]) -> str:
    return "; ".join(
        f"{g['label']} ({g['first_s']:.1f}–{g['last_s']:.1f} s)" for g in rep["guidance"]
    )


def repetition_content(run, recording, reading) -> dict[str, Any]:
    """The repetition table (times in seconds, the reading's verdicts, guidance) and the
    timeline's layers."""
    names = recording.exercise.landmark_type_names if recording.exercise else {}
    line = timeline(
        run.result, {str(k): str(v) for k, v in (names or {}).items()}, run.summary,
        fallback_frames=recording.n_frames or 0, reading=reading,
    )  # fmt: skip
    rows = [
        [r["number"], f"{r['first_s']:.1f}–{r['last_s']:.1f}", r["score"], r["verdict"],
         guidance_text(r) or "none"]
        for r in line["repetitions"]
    ]  # fmt: skip
    return {"repetitions": rows, "timeline": line}


def passed_line(reading) -> str:
    """The pass count as every page says it ("4 of 10 repetitions passed")."""
    if not reading.fits:
        return "No repetition was counted: the recording does not show the exercise."
    return f"{reading.passed_count} of {reading.repetition_count} repetitions passed"


def recording_content(recording) -> dict[str, Any]:
    run = recording.latest_succeeded_run()
    exercise = recording.exercise.name if recording.exercise else "no exercise"
    content: dict[str, Any] = {
        "title": f"Recording report · {recording.patient.display_name}",
        "header": [
            f"Clinic: {recording.clinic.name}",
            f"Patient: {recording.patient.display_name} · Exercise: {exercise}",
            f"Recorded {recording.uploaded_at:%d %b %Y %H:%M} · {recording.duration_s:.1f} s at "
            f"{recording.fps:.0f} frames per second · report made {timezone.now():%d %b %Y %H:%M}",
        ],
        "analysed": run is not None and run.result is not None,
        "notes": note_lines(recording),
    }
    if not content["analysed"]:
        return content
    result, reading = run.result, reading_of(run)
    if reading is None:  # a summary that cannot be read: the report says it was not analysed
        return {**content, "analysed": False}
    content["score"] = fmt(reading.score)
    content["passed_line"] = passed_line(reading)
    content.update(repetition_content(run, recording, reading))
    said = reading.statements
    # no score and no repetition: say why first; then what to correct (the reading's statements)
    content["feedback"] = [*([said["message"]] if said.get("message") else []), *said["to_correct"]]
    content["went_well"] = said.get("went_well", [])
    content["therapist"] = said.get("therapist", [])
    content.update(clinical_content(result, recording.exercise))
    content["rom"] = [
        [body_part(joint).capitalize(), fmt(value, 1), fmt(result.gamma.get(joint), 2)]
        for joint, value in result.range_of_motion.items()
    ]
    content["poses"], content["parents"] = key_poses(run)
    return content


def parse_day(value: str | None) -> date | None:
    try:
        return date.fromisoformat(value) if value else None
    except ValueError:
        return None


def session_days(points: list[dict]) -> tuple[date | None, list[float]]:
    """The report's first day and each session's place on a day axis (days since that day's
    midnight; the sessions of one day spread within it, as on the progress page)."""
    moments = [datetime.fromisoformat(p["date"]) for p in points]
    if not moments:
        return None, []
    first = min(m.date() for m in moments)
    start = datetime.combine(first, datetime.min.time())
    placed = [datetime.fromisoformat(x) for x in session_x(moments)]
    return first, [round((x - start).total_seconds() / 86400.0, 4) for x in placed]


def series_by_exercise(points: list[dict], field: str) -> dict[str, list[tuple[float, float]]]:
    """Per exercise, (day, value) of each session with a value; the MAX_LINES exercises with the
    most sessions (x: days since the report's first day)."""
    _, days = session_days(points)
    series: dict[str, list[tuple[float, float]]] = {}
    for day, point in zip(days, points, strict=True):
        if point.get(field) is not None:
            series.setdefault(point["exercise_name"] or "?", []).append((day, point[field]))
    kept = sorted(series, key=lambda name: -len(series[name]))[:MAX_LINES]
    return {name: series[name] for name in series if name in kept}


def _rom_by_angle(points: list[dict]) -> dict[str, dict[str, list[tuple[float, float]]]]:
    """Per exercise, by angle name, (day, range) of the MAX_ROM_LINES clinical angles it moves
    most (x: days since the report's first day)."""
    _, days = session_days(points)
    charts: dict[str, dict[str, list[tuple[float, float]]]] = {}
    for day, point in zip(days, points, strict=True):
        series = charts.setdefault(point.get("exercise_name") or "Unknown exercise", {})
        for angle, span in (point.get("clinical_angles") or {}).items():
            series.setdefault(angle, []).append((day, float(span["range"])))
    return {
        exercise: {
            angle: series[angle]
            for angle in most_moved(
                {a: [v for _, v in line] for a, line in series.items()}, MAX_ROM_LINES
            )
        }
        for exercise, series in charts.items()
    }


def rom_series(points: list[dict]) -> dict[str, dict[str, list[tuple[float, float]]]]:
    """Per exercise, the range of the (up to) MAX_ROM_LINES clinical angles it moves most over
    the sessions, by the angle's name in words (the ranges of the recording's table of angles):
    a line only ever joins sessions of one exercise."""
    return {
        exercise: {angle_label(angle): line for angle, line in series.items()}
        for exercise, series in _rom_by_angle(points).items()
    }


def rom_norms(points: list[dict]) -> dict[str, str]:
    """Per exercise, the normal adult ranges of the angles its chart shows, in words."""
    out = {}
    for exercise, series in _rom_by_angle(points).items():
        named = [angle_line_label(angle) for angle in series]
        if named:
            out[exercise] = "Each line's normal adult range: " + "; ".join(named) + "."
    return out


def progress_content(patient, since: date | None, until: date | None) -> dict[str, Any]:
    points = patient_progress(patient, since=since, until=until)
    period = f"{since or 'start'} to {until or 'today'}"
    return {
        "title": f"Progress report · {patient.display_name}",
        "header": [
            f"Clinic: {patient.clinic.name}",
            f"Patient: {patient.display_name} · period {period} · {len(points)} sessions",
            f"Report made {timezone.now():%d %b %Y %H:%M}",
        ],
        "points": points,
        "rows": [
            [
                p["date"][:10],
                p["exercise_name"] or "",
                fmt(p["score"]),
                p["repetitions"],
                "–" if p["pain_score"] is None else p["pain_score"],
            ]
            for p in points
        ],
        "first_day": session_days(points)[0],
        "score_series": series_by_exercise(points, "score"),
        "rom_series": rom_series(points),
        "rom_norms": rom_norms(points),
        "goals": goal_rows(patient),
    }


def goal_rows(patient) -> list[list[str]]:
    """Each goal (over all the patient's sessions, not only the report's period): exercise,
    the goal in words, the latest value, and whether it is met or on track."""
    return [
        [found.goal.exercise.name, found.words, found.latest_words(), found.state_words]
        for found in patient_goal_statuses(patient)
    ]
