"""Goals on the progress charts in a real browser: a score goal and a knee-angle goal appear as
dashed lines labelled "goal" with their unit, on the score chart and on the exercise's joint
angle chart respectively (and not on the other one)."""

from __future__ import annotations

import pytest

from analysis.pipeline.results import AngleRange
from tests.e2e.test_clinical_angles_pages import sign_in
from tests.personas import make_exercise, make_world
from tests.webapp.test_clinical_pages import analysed, summary
from webapp.patients.models import Goal

pytestmark = pytest.mark.e2e


@pytest.fixture
def patient_with_goals(transactional_db, eager_celery):
    world = make_world()
    squat = make_exercise(world.clinic)
    for days_ago, knee, score in ((9, 70.0, 60.0), (2, 80.0, 72.0)):
        angles = {"knee_flexion_left": AngleRange(0.0, knee)}
        analysed(world.patient, squat, summary(score, angles), days_ago=days_ago)
    for measure, target in (("score", 85.0), ("knee_flexion_left", 90.0)):
        Goal.objects.create(
            patient=world.patient, exercise=squat, measure=measure, target=target, by="2027-03-12"
        )
    return world


def dashed_lines(chart) -> int:
    """Dashed lines drawn in the plot area (the legend repeats each line's style)."""
    return chart.locator(".scatterlayer path.js-line[style*='stroke-dasharray']").count()


def test_goals_are_dashed_labelled_lines_on_the_matching_charts(
    page, live_server, patient_with_goals
):
    world = patient_with_goals
    sign_in(page, live_server.url)
    page.goto(f"{live_server.url}/patients/{world.patient.pk}/progress/")
    page.wait_for_selector("#progress[data-ready='1']")
    page.wait_for_selector("#clinical-progress[data-ready='1']")

    score = page.locator("#chart-score")
    assert score.locator(".legendtext", has_text="goal 85 points").count() == 1
    assert score.locator(".textpoint", has_text="goal 85 points").count() == 1
    assert dashed_lines(score) == 1
    assert score.locator(".legendtext", has_text="goal 90°").count() == 0

    angles = page.locator(".clinical-angles-chart").first
    assert angles.locator(".legendtext", has_text="goal 90°").count() == 1
    assert angles.locator(".textpoint", has_text="goal 90°").count() == 1
    assert dashed_lines(angles) == 1
    assert angles.locator(".legendtext", has_text="points").count() == 0
