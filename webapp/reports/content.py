"""What a report says, as plain data shared by the PDF and the printable HTML."""

from __future__ import annotations

from datetime import date
from typing import Any

from django.utils import timezone

from webapp.patients.progress import patient_progress
from webapp.reports import playback
from webapp.reports.clinical import clinical_content
from webapp.reports.timeline import timeline

MAX_POSES = 4


def fmt(value: Any, digits: int = 0) -> str:
    return "–" if value is None else f"{float(value):.{digits}f}"


def key_poses(run) -> tuple[list, list[int]]:
    try:
        arrays = playback.load_arrays(run)
    except (OSError, ValueError, KeyError):
        return [], []
    positions = arrays["patient_positions"]
    kinds = playback.type_names(run)
    poses = []
    for mark in run.result.landmarks[:MAX_POSES]:
        frame = min(mark.frame, positions.shape[0] - 1)
        name = kinds.get(str(mark.type), f"pose {mark.type}")
        poses.append((f"{name} · frame {frame}", positions[frame]))
    return poses, [int(p) for p in arrays["parents"]]


def guidance_text(rep: dict[str, Any]) -> str:
    return "; ".join(
        f"{g['label']} ({g['first_s']:.1f}–{g['last_s']:.1f} s)" for g in rep["guidance"]
    )


def repetition_content(run, recording) -> dict[str, Any]:
    """The repetition table (times in seconds, pass/fail, guidance) and the timeline's layers."""
    names = recording.exercise.landmark_type_names if recording.exercise else {}
    line = timeline(
        run.result, {str(k): str(v) for k, v in (names or {}).items()}, run.summary,
        fallback_frames=recording.n_frames or 0,
    )  # fmt: skip
    rows = [
        [r["number"], f"{r['first_s']:.1f}–{r['last_s']:.1f}", r["score"], r["verdict"],
         guidance_text(r) or "none"]
        for r in line["repetitions"]
    ]  # fmt: skip
    return {"repetitions": rows, "timeline": line}


def recording_content(recording) -> dict[str, Any]:
    run = recording.latest_succeeded_run()
    exercise = recording.exercise.name if recording.exercise else "no exercise"
    content: dict[str, Any] = {
        "title": f"Recording report · {recording.patient.display_name}",
        "header": [
            f"Clinic: {recording.clinic.name}",
            f"Patient: {recording.patient.display_name} · Exercise: {exercise}",
            f"Recorded {recording.uploaded_at:%d %b %Y %H:%M} · {recording.n_frames} frames at "
            f"{recording.fps:.0f} fps · report made {timezone.now():%d %b %Y %H:%M}",
        ],
        "analysed": run is not None and run.result is not None,
    }
    if not content["analysed"]:
        return content
    result = run.result
    content["score"] = fmt(result.score)
    content.update(repetition_content(run, recording))
    content["feedback"] = [comment.text for comment in result.feedback]
    content.update(clinical_content(result, recording.exercise))
    content["rom"] = [
        [joint, fmt(value, 1), fmt(result.gamma.get(joint), 2)]
        for joint, value in result.range_of_motion.items()
    ]
    content["poses"], content["parents"] = key_poses(run)
    return content


def parse_day(value: str | None) -> date | None:
    try:
        return date.fromisoformat(value) if value else None
    except ValueError:
        return None


def series_by_exercise(points: list[dict], field: str) -> dict[str, list[tuple[float, float]]]:
    series: dict[str, list[tuple[float, float]]] = {}
    for i, point in enumerate(points):
        if point.get(field) is not None:
            series.setdefault(point["exercise_name"] or "?", []).append((i + 1, point[field]))
    return series


def rom_series(points: list[dict]) -> dict[str, list[tuple[float, float]]]:
    series: dict[str, list[tuple[float, float]]] = {}
    for i, point in enumerate(points):
        for joint, value in (point.get("range_of_motion") or {}).items():
            series.setdefault(joint, []).append((i + 1, float(value)))
    return dict(list(series.items())[:5])


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
        "score_series": series_by_exercise(points, "score"),
        "rom_series": rom_series(points),
    }
