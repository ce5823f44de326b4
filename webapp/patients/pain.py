"""Pain over time: the pain score (0–10) the patient gave with each recording, as a chart.

Drawn on the server as SVG (the patient page loads no chart library): one point per session
placed by date, sessions of one day side by side (`session_x`), days labelled "12 Nov".
"""

from __future__ import annotations

from datetime import datetime, timedelta
from typing import Any

from django.utils import timezone

from webapp.patients.models import Patient
from webapp.patients.progress import date_axis, session_x
from webapp.recordings.models import Recording

WIDTH, HEIGHT = 640, 220
LEFT, RIGHT, TOP, BOTTOM = 56, 12, 12, 44  # room for the axis titles and tick labels
PAIN_MAX = 10
MAX_SESSIONS = 200  # the newest ones: older pain is in the recordings list


def pain_series(patient: Patient) -> list[dict[str, Any]]:
    """Each recording with a pain score, oldest first: when (local time), score, exercise."""
    rows = list(
        Recording.objects.filter(patient=patient, pain_score__isnull=False)
        .order_by("-uploaded_at")
        .values("pk", "uploaded_at", "pain_score", "exercise__name")[:MAX_SESSIONS]
    )
    return [
        {
            "recording": str(row["pk"]),
            "moment": timezone.localtime(row["uploaded_at"]).replace(tzinfo=None),
            "score": row["pain_score"],
            "exercise": row["exercise__name"] or "exercise to confirm",
        }
        for row in reversed(rows)
    ]


def pain_chart(patient: Patient) -> dict[str, Any]:
    return pain_layout(pain_series(patient))


def pain_layout(series: list[dict[str, Any]]) -> dict[str, Any]:
    """Pixel positions of the points, the line, the day ticks and the 0–10 ticks."""
    axis = date_axis([s["moment"].date() for s in series])
    start, end = (datetime.fromisoformat(v) for v in axis["range"])
    span = (end - start).total_seconds()
    plot_w, plot_h = WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM

    def x_of(moment: datetime) -> float:
        return round(LEFT + plot_w * (moment - start).total_seconds() / span, 1)

    def y_of(score: float) -> float:
        return round(TOP + plot_h * (1 - score / PAIN_MAX), 1)

    points = [
        {
            **s,
            "x": x_of(datetime.fromisoformat(placed)),
            "y": y_of(s["score"]),
            "when": f"{s['moment']:%-d %b %Y %H:%M}",
        }
        for s, placed in zip(series, session_x([s["moment"] for s in series]), strict=True)
    ]
    days = _tick_days(datetime.fromisoformat(axis["tick0"]), end, axis["dtick"])
    return {
        "width": WIDTH,
        "height": HEIGHT,
        "left": LEFT,
        "right": WIDTH - RIGHT,
        "top": TOP,
        "bottom": HEIGHT - BOTTOM,
        "points": points,
        "line": " ".join(f"{p['x']},{p['y']}" for p in points),
        "x_ticks": [{"x": x_of(d), "text": f"{d:%-d %b}"} for d in days],
        "y_ticks": [{"y": y_of(v), "text": str(v)} for v in range(0, PAIN_MAX + 1, 2)],
    }


def _tick_days(first: datetime, end: datetime, step_ms: int) -> list[datetime]:
    step = timedelta(milliseconds=step_ms)
    days, moment = [], first
    while moment < end:
        days.append(moment)
        moment += step
    return days
