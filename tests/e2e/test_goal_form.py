"""The goal form in a real browser: "Add goal" with the date the form offers saves the goal
(the date input holds an ISO date the browser accepts), and a knee target no body reaches (300°)
is refused with a message that says why."""

from __future__ import annotations

import datetime

import pytest
from django.utils import timezone
from django.utils.dateformat import format as format_date

from tests.e2e.conftest import log_in
from tests.personas import PASSWORD, make_exercise, make_world
from webapp.patients.models import Goal

pytestmark = pytest.mark.e2e


def test_a_goal_added_with_the_default_date_and_300_degrees_refused(
    page, live_server, transactional_db
):
    world = make_world()
    make_exercise(world.clinic)
    log_in(page, live_server.url, "therapist", PASSWORD)
    page.goto(f"{live_server.url}/patients/{world.patient.pk}/")
    form = page.locator("#add-goal")
    by = timezone.localdate() + datetime.timedelta(weeks=6)
    assert form.locator("input[name=by]").input_value() == by.isoformat()
    form.locator("select[name=measure]").select_option("knee_flexion_left")
    form.locator("input[name=target]").fill("300")
    form.locator("button").click()
    page.wait_for_load_state()
    refused = page.locator(".messages, .message, [role=alert]").first.inner_text()
    assert "no body moves that joint further" in refused and "180°" in refused, refused
    assert not Goal.objects.exists()
    form = page.locator("#add-goal")
    form.locator("select[name=measure]").select_option("knee_flexion_left")
    form.locator("input[name=target]").fill("90")
    form.locator("button").click()
    page.wait_for_selector("#goals .goal")
    words = page.locator("#goals .goal-words").inner_text()
    assert words == f"Left knee flexion: reach 90° range of motion by {format_date(by, 'j F Y')}"
