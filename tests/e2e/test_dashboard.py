"""The home page in a real browser: who needs attention, recent recordings, and an analysis whose
progress moves on the page without a reload; the patient's own simpler home.

With E2E_DOCS=1 (`make bench-browser`) the therapist's home is saved to docs/img/dashboard-home.png.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.e2e.conftest import log_in

pytestmark = pytest.mark.e2e
DOCS = Path(__file__).resolve().parents[2] / "docs" / "img"


def fail_newest_run(patient_name: str):
    """A re-analysis of the patient's newest recording that failed (written with the ORM, so the
    stored attention list is refreshed as the worker that finishes a run refreshes it)."""
    from webapp.dashboard.precompute import refresh_after_run
    from webapp.recordings.models import AnalysisRun, Recording, RunStatus

    recording = Recording.objects.filter(patient__display_name=patient_name).first()
    run = AnalysisRun.objects.create(
        recording=recording, status=RunStatus.FAILED, user_error="The file could not be read."
    )
    refresh_after_run(run.pk)
    return run


def queue_run(patient_name: str):
    from webapp.recordings.models import AnalysisRun, Recording

    recording = Recording.objects.filter(patient__display_name=patient_name).last()
    return AnalysisRun.objects.create(recording=recording)


def set_run(run, **fields) -> None:
    from webapp.recordings.models import AnalysisRun

    AnalysisRun.objects.filter(pk=run.pk).update(**fields)


def test_home_follows_an_analysis_live_and_patients_see_their_own(page, live_server, demo):
    failed = fail_newest_run("Robin Second")
    log_in(page, live_server.url)
    page.goto(f"{live_server.url}/")
    page.evaluate("window.notReloaded = true")

    robin = page.locator(".attention-item", has_text="Robin Second")
    assert robin.locator(".reason-failed").count() == 1
    assert f"/recordings/{failed.recording_id}/" in robin.locator(".reason-failed a").get_attribute(
        "href"
    )
    assert page.locator(".attention-item .reason-adherence").count() >= 1
    scores = page.locator("#recent-rows td.score").all_inner_texts()
    assert any(text.isdigit() for text in scores), scores
    assert page.locator("#active-list .run").count() == 0

    run = queue_run("Pat Patient")
    row = page.locator(f'#active-list [data-run="{run.pk}"]')
    row.wait_for(timeout=20_000)  # picked up by the page's own polling
    assert "Pat Patient" in row.inner_text()

    set_run(run, status="running", stage="alignment", progress=60)
    page.wait_for_function(
        f"""document.querySelector('[data-run="{run.pk}"] .bar').style.width === '60%'"""
    )
    assert row.locator(".run-state").inner_text() == "Running · alignment"
    if os.environ.get("E2E_DOCS"):
        DOCS.mkdir(parents=True, exist_ok=True)
        page.wait_for_timeout(800)  # let the bar's width transition finish
        page.screenshot(path=str(DOCS / "dashboard-home.png"), full_page=True)

    set_run(run, status="succeeded", stage="done", progress=100, summary={"score": 77})
    page.wait_for_selector(f'#active-list [data-run="{run.pk}"].finished')
    newest = page.locator(f'#recent-rows tr[data-recording="{run.recording_id}"]')
    newest.locator("text=Succeeded").wait_for()
    assert newest.locator("td.score").inner_text() == "77"
    assert page.evaluate("window.notReloaded") is True  # all of it without a page load

    # The same clinic seen by the demo patient (one demo load serves both: it takes a while).
    page.context.clear_cookies()
    log_in(page, live_server.url, "demo-patient")
    page.goto(f"{live_server.url}/")
    assert page.locator("#prescriptions li").count() == 2  # Deep squat, Shoulder abduction
    assert "Last 4 weeks:" in page.inner_text("#prescriptions")
    assert page.locator("#attention").count() == 0
    assert "Robin Second" not in page.content()
    assert page.locator("#recent-rows tr").count() == 4
