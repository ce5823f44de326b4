"""The progress charts' data (issue 23, item 6): one point per session placed by date, sessions
of one day side by side, at most four lines per chart (the body parts and angles the exercise
moves most), a sane whole-day date axis even for a single session, units on the axes."""

from __future__ import annotations

import datetime
import json
import re
from pathlib import Path

import pytest
from django.urls import reverse
from django.utils import timezone

from analysis.pipeline.results import AnalysisSummary, AngleRange
from tests.personas import make_exercise, make_recording
from webapp.patients.progress import (
    MAX_LINES,
    clinical_progress,
    date_axis,
    most_moved,
    progress_charts,
    session_x,
)
from webapp.recordings.models import AnalysisRun, Recording, RunStatus

JOINTS = [f"Joint{i}" for i in range(13)]  # thirteen body parts: the thirteen lines


def result(score: float, scale: float) -> dict:
    """A summary whose body part i moves 10·i degrees (times `scale`): the last ones move most."""
    rom = {joint: 10.0 * i * scale for i, joint in enumerate(JOINTS)}
    angles = {
        "knee_flexion_left": AngleRange(0.0, 90.0 * scale),
        "knee_flexion_right": AngleRange(0.0, 85.0 * scale),
        "hip_flexion_left": AngleRange(0.0, 60.0 * scale),
        "hip_flexion_right": AngleRange(0.0, 55.0 * scale),
        "trunk_flexion": AngleRange(0.0, 20.0 * scale),
        "ankle_dorsiflexion_left": AngleRange(0.0, 5.0 * scale),
    }
    summary = AnalysisSummary(
        frames=40, fps=30.0, landmarks=(), repetitions=(), score=score,
        range_of_motion=rom, gamma={j: 0.5 for j in JOINTS}, clinical_angles=angles,
    )  # fmt: skip
    return summary.to_json()


def session(patient, exercise, when: datetime.datetime, score: float = 70.0) -> Recording:
    recording = make_recording(patient, exercise)
    AnalysisRun.objects.filter(recording=recording).update(
        status=RunStatus.SUCCEEDED, summary=result(score, 1.0), score=score
    )
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when)
    return recording


def at(days_ago: int, hour: int) -> datetime.datetime:
    day = timezone.localdate() - datetime.timedelta(days=days_ago)
    return timezone.make_aware(datetime.datetime.combine(day, datetime.time(hour)))


@pytest.fixture
def history(world):
    squat = make_exercise(world.clinic)
    for days_ago, hour in ((9, 9), (5, 8), (5, 12), (5, 18), (1, 10)):
        session(world.patient, squat, at(days_ago, hour), score=60.0 + days_ago)
    return world


def test_thirteen_body_parts_give_four_lines_the_ones_moved_most(history):
    """Range of motion: the clinical angles the exercise moves most (a squat: knees and hips,
    never feet), their ranges those of the recording's table; levels: the body parts."""
    (chart,) = progress_charts(history.patient)
    assert len(chart["rom"]) == MAX_LINES and len(chart["gamma"]) == MAX_LINES
    assert [line["label"] for line in chart["rom"]] == [
        "Left knee flexion (normal 0° to 135°)",
        "Right knee flexion (normal 0° to 135°)",
        "Left hip flexion (normal -30° to 120°)",
        "Right hip flexion (normal -30° to 120°)",
    ]
    assert [max(line["y"]) for line in chart["rom"]] == [90.0, 85.0, 60.0, 55.0]
    assert all(len(line["y"]) == 5 for line in chart["rom"])
    assert not any("foot" in line["label"].lower() for line in chart["rom"])
    assert not any("Joint" in line["label"] and "_" in line["label"] for line in chart["gamma"])


def test_one_point_per_session_and_same_day_sessions_side_by_side(history):
    (chart,) = progress_charts(history.patient)
    assert len(chart["x"]) == len(chart["score"]) == len(chart["when"]) == 5
    assert len(set(chart["x"])) == 5  # three sessions of one day: three distinct places
    assert chart["x"] == sorted(chart["x"])
    same_day = chart["x"][1:4]
    assert len({x[:10] for x in same_day}) == 1  # ...all within their own day
    assert [w[-5:] for w in chart["when"][1:4]] == ["08:00", "12:00", "18:00"]  # tooltip time


def test_clinical_chart_shows_four_angles_and_the_normal_band(history):
    (exercise,) = clinical_progress(history.patient)
    shown = [a["name"] for a in exercise["angles"] if a["shown"]]
    assert sorted(shown) == sorted(
        ["knee_flexion_left", "knee_flexion_right", "hip_flexion_left", "hip_flexion_right"]
    )
    assert len(exercise["angles"]) == 6  # every angle stays in the table of values
    band = exercise["band"]
    assert band["low"] < band["high"] and band["text"].endswith("°")
    assert len(set(exercise["x"])) == 5


def test_a_single_session_gives_a_whole_day_axis():
    day = datetime.date(2026, 11, 12)
    axis = date_axis([day])
    start, end = (datetime.datetime.fromisoformat(v) for v in axis["range"])
    assert datetime.timedelta(days=1) <= end - start <= datetime.timedelta(days=3)
    assert axis["dtick"] == 86_400_000  # one day between ticks, never fractions of a second
    assert axis["tickformat"] == "%-d %b"
    (x,) = session_x([datetime.datetime(2026, 11, 12, 23, 59, 59)])
    assert start < datetime.datetime.fromisoformat(x) < end


def test_a_long_history_keeps_eight_ticks_at_most():
    days = [datetime.date(2026, 1, 1) + datetime.timedelta(days=d) for d in range(0, 300, 3)]
    axis = date_axis(days)
    start, end = (datetime.datetime.fromisoformat(v) for v in axis["range"])
    ticks = (end - start) / datetime.timedelta(milliseconds=axis["dtick"])
    assert ticks <= 9


def test_most_moved_ignores_missing_values():
    assert most_moved({"a": [None, 5.0], "b": [None, None], "c": [30.0, 1.0]}, 2) == ["c", "a"]


def test_progress_page_has_the_chart_data_and_units(client, history):
    client.force_login(history.therapist)
    html = client.get(reverse("reports:progress", kwargs={"pk": history.patient.pk})).content
    html = html.decode()
    data = re.search(r'id="progress-charts"[^>]*>(.*?)</script>', html, re.S).group(1)
    (chart,) = json.loads(data)
    assert len(chart["rom"]) <= MAX_LINES and chart["axis"]["tickformat"] == "%-d %b"
    script = (Path(__file__).parents[2] / "webapp/static/js/progress.js").read_text("utf-8")
    for unit in ("score (0–100)", "range of motion (°)", "level (0–1)", "repetitions (count)"):
        assert f'"{unit}"' in script  # each chart's y-axis title names its unit
    assert "degrees" in html and "(0–100)" in html
