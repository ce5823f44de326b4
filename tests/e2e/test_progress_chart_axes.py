"""The progress charts in a real browser (issue 23, item 6): date ticks read "12 Nov" (a single
session gives whole days, never sub-second ticks), the legend covers no axis title, every axis
says its unit, at most four lines per chart, and sessions of one day are drawn side by side."""

from __future__ import annotations

import datetime
import os
import re

import pytest
from django.utils import timezone

from analysis.pipeline.results import AnalysisSummary, AngleRange
from tests.e2e.test_clinical_angles_pages import sign_in
from tests.personas import make_exercise, make_recording, make_world
from webapp.recordings.models import AnalysisRun, Recording, RunStatus

pytestmark = pytest.mark.e2e
DAY_TICK = re.compile(r"^\d{1,2} (Jan|Feb|Mar|Apr|May|Jun|Jul|Aug|Sep|Oct|Nov|Dec)$")


def session(patient, exercise, when: datetime.datetime) -> None:
    rom = {f"Joint{i}": 10.0 * i for i in range(13)}
    angles = {name: AngleRange(0.0, 40.0 + 10 * i) for i, name in enumerate(
        ("knee_flexion_left", "knee_flexion_right", "hip_flexion_left", "hip_flexion_right",
         "trunk_flexion"))}  # fmt: skip
    summary = AnalysisSummary(
        frames=40, fps=30.0, landmarks=(), repetitions=(), score=70.0,
        range_of_motion=rom, gamma={j: 0.5 for j in rom}, clinical_angles=angles,
    ).to_json()  # fmt: skip
    recording = make_recording(patient, exercise)
    AnalysisRun.objects.filter(recording=recording).update(
        status=RunStatus.SUCCEEDED, summary=summary, score=70.0
    )
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when)


def at(days_ago: int, hour: int) -> datetime.datetime:
    day = timezone.localdate() - datetime.timedelta(days=days_ago)
    return timezone.make_aware(datetime.datetime.combine(day, datetime.time(hour)))


def boxes_overlap(a: dict, b: dict) -> bool:
    return (
        a["x"] < b["x"] + b["width"] and b["x"] < a["x"] + a["width"]
        and a["y"] < b["y"] + b["height"] and b["y"] < a["y"] + a["height"]
    )  # fmt: skip


def open_progress(page, base_url: str, patient) -> None:
    page.set_viewport_size({"width": 1200, "height": 900})
    page.goto(f"{base_url}/patients/{patient.pk}/progress/")
    page.wait_for_selector("#progress[data-ready='1']")
    page.wait_for_selector("#clinical-progress[data-ready='1']")


def check_chart(chart) -> list[str]:
    """The chart's x tick labels, after checking its titles, units and legend."""
    assert chart.locator(".g-xtitle").text_content() == "date of the session"
    assert re.search(r"\((°|0–100|0–1|count)\)|%", chart.locator(".g-ytitle").text_content())
    if chart.locator(".legend").count():  # one line alone has no legend
        legend = chart.locator(".legend").bounding_box()
        for title in (".g-xtitle", ".g-ytitle"):
            assert not boxes_overlap(legend, chart.locator(title).bounding_box()), title
    return chart.locator(".xtick text").all_text_contents()


@pytest.fixture
def one_session(transactional_db, eager_celery):
    world = make_world()
    session(world.patient, make_exercise(world.clinic), at(1, 23))
    return world


@pytest.fixture
def same_day(transactional_db, eager_celery):
    world = make_world()
    squat = make_exercise(world.clinic)
    for days_ago, hour in ((6, 9), (3, 8), (3, 12), (3, 18), (1, 10)):
        session(world.patient, squat, at(days_ago, hour))
    return world


def test_a_single_session_gives_day_ticks(page, live_server, one_session):
    sign_in(page, live_server.url)
    open_progress(page, live_server.url, one_session.patient)
    for chart in ("#chart-score", "#chart-rom", "#chart-gamma", ".clinical-angles-chart"):
        ticks = check_chart(page.locator(chart).first)
        assert ticks and all(DAY_TICK.match(t) for t in ticks), (chart, ticks)


def test_same_day_sessions_stand_apart_with_four_lines_at_most(page, live_server, same_day):
    sign_in(page, live_server.url)
    open_progress(page, live_server.url, same_day.patient)
    for chart in ("#chart-score", "#chart-rom", "#chart-gamma", ".clinical-angles-chart"):
        ticks = check_chart(page.locator(chart).first)
        assert all(DAY_TICK.match(t) for t in ticks), (chart, ticks)
    rom = page.locator("#chart-rom")
    assert rom.locator(".scatterlayer .trace").count() == 4
    xs = page.evaluate("() => document.getElementById('chart-score').data[0].x")
    assert len(xs) == 5 and len(set(xs)) == 5
    if os.environ.get("E2E_SHOTS"):
        page.screenshot(path=os.environ["E2E_SHOTS"], full_page=True)
