"""A therapist uploads a UI-PRMD session and reviews it in a real browser."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.e2e.conftest import log_in

SESSION = Path(__file__).resolve().parents[2] / "data/ui-prmd/sessions/m01_s01_correct.bvh.gz"
pytestmark = pytest.mark.e2e


def canvas_pixels(page) -> str:
    return page.evaluate("document.getElementById('viewer-canvas').toDataURL()")


def upload_session(page, base_url: str) -> None:
    page.goto(f"{base_url}/recordings/upload/")
    page.select_option("#id_patient", index=1)
    page.select_option("#id_exercise", label="Deep squat")
    page.set_input_files("#id_file", str(SESSION))
    page.click("button[type=submit]")
    page.wait_for_url("**/recordings/*/")
    # Progress is polled from the status endpoint until the run ends; the page then reloads.
    page.wait_for_function(
        "document.getElementById('run-status').dataset.status === 'succeeded'", timeout=180_000
    )
    page.wait_for_selector("#viewer[data-ready='1']")


def test_upload_play_jump_and_download_report(page, live_server, demo):
    log_in(page, live_server.url)
    upload_session(page, live_server.url)
    assert page.inner_text("#run-state") == "Succeeded"

    before, cursor_before = (
        canvas_pixels(page),
        page.eval_on_selector("#timeline-cursor", "e => e.style.left"),
    )
    page.click("#play")
    page.wait_for_function("window.physioPlayback.frame > 15")
    assert canvas_pixels(page) != before
    assert page.eval_on_selector("#timeline-cursor", "e => e.style.left") != cursor_before
    page.click("#play")  # pause

    landmark = page.locator("#timeline .landmark").nth(2)
    target = int(landmark.get_attribute("data-frame"))
    landmark.click()
    assert page.evaluate("window.physioPlayback.frame") == target
    fps = page.evaluate("window.physioPlayback.meta.fps")
    assert page.inner_text("#frame-label") == f"{target / fps:.2f} s"  # seconds, not frames

    page.select_option("#speed", "0.25")  # slow, so the jump back is seen before it plays on
    page.evaluate(f"window.physioPlayback.setFrame({target + 8})")
    page.click("#replay-key")  # back to the key pose just passed, and play from there
    assert page.evaluate("window.physioPlayback.playing")
    assert target <= page.evaluate("window.physioPlayback.frame") < target + 8
    page.click("#play")  # pause

    with page.expect_download() as download:
        page.click("#report-pdf")
    body = Path(download.value.path()).read_bytes()
    assert body.startswith(b"%PDF") and body.rstrip().endswith(b"%%EOF")
    assert body.count(b"/Type /Page\n") + body.count(b"/Type /Page ") >= 1
