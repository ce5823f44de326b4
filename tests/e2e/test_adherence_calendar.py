"""The adherence calendar in a real browser: each session's cell is the day it was recorded in
the clinic's time zone (a late-evening session included), whatever the browser's own time zone;
its columns are weeks starting on Monday, its rows Monday to Sunday."""

from __future__ import annotations

import datetime

import pytest
from django.utils import timezone

from tests.e2e.conftest import log_in
from tests.e2e.test_progress_chart_axes import session
from tests.personas import PASSWORD, make_exercise, make_world

pytestmark = pytest.mark.e2e
CLINIC_ZONE = "America/Chicago"  # west of UTC: an evening session is the next day in UTC
CELLS = """() => {
  const trace = document.getElementById("chart-adherence").data[0];
  const shown = [];
  trace.z.forEach((row, r) => row.forEach((n, c) => {
    if (n > 0) shown.push(trace.customdata[r][c]);
  }));
  return shown;
}"""


def local(days_ago: int, hour: int, minute: int = 0) -> datetime.datetime:
    day = timezone.localdate() - datetime.timedelta(days=days_ago)
    return timezone.make_aware(datetime.datetime.combine(day, datetime.time(hour, minute)))


def words(day: datetime.date) -> str:
    return f"{day:%a} {day.day} {day:%b} {day.year}"


@pytest.fixture
def sessions(transactional_db, eager_celery, settings):
    settings.TIME_ZONE = CLINIC_ZONE
    timezone.activate(CLINIC_ZONE)
    world = make_world()
    squat = make_exercise(world.clinic)
    moments = [local(20, 9), local(12, 23, 30), local(3, 0, 30)]
    for moment in moments:
        session(world.patient, squat, moment)
    yield world, sorted(words(m.date()) for m in moments)
    timezone.deactivate()


@pytest.mark.parametrize("browser_zone", ["Asia/Tokyo", "America/Los_Angeles"])
def test_each_session_on_the_day_it_was_recorded(browser, live_server, sessions, browser_zone):
    world, expected = sessions
    context = browser.new_context(viewport={"width": 1200, "height": 900}, timezone_id=browser_zone)
    page = context.new_page()
    try:
        log_in(page, live_server.url, "therapist", PASSWORD)
        page.goto(f"{live_server.url}/patients/{world.patient.pk}/progress/")
        page.wait_for_selector("#progress[data-ready='1']")
        assert sorted(page.evaluate(CELLS)) == expected
        today = timezone.localdate()
        first = today - datetime.timedelta(days=today.weekday() + 77)
        mondays = {f"{first + datetime.timedelta(weeks=w):%-d %b}" for w in range(12)}
        ticks = page.locator("#chart-adherence .xtick text").all_text_contents()
        assert ticks and set(ticks) <= mondays, ticks
        rows = page.locator("#chart-adherence .ytick text").all_text_contents()
        assert rows == ["Mon", "Tue", "Wed", "Thu", "Fri", "Sat", "Sun"] or rows[::-1] == [
            "Mon", "Tue", "Wed", "Thu", "Fri", "Sat", "Sun"]  # fmt: skip
        assert "clinic's time zone" in page.locator("#progress").inner_text()
    finally:
        context.close()
