"""The recording page's timeline in a real browser: three key-pose layers with toggles, guidance
markers in plain words, pass/fail per repetition and the note when repetitions were cut without a
key-pose cycle. The run's result is written directly (what the worker stores), so the page is
tested on a recording that surely has every layer and guidance."""

from __future__ import annotations

import pytest
from django.core.files.base import ContentFile

from tests.e2e.conftest import log_in as sign_in
from tests.personas import PASSWORD, make_exercise, make_recording, make_world
from tests.webapp.test_reports import npz
from webapp.recordings.models import RunStatus

pytestmark = pytest.mark.e2e

SUMMARY = {
    "frames": 40, "fps": 20.0, "score": 52.0, "segmentation": "fallback", "pass_threshold": 50.0,
    "landmarks": [
        {"frame": 3, "type": 1, "origin": "identified"},
        {"frame": 20, "type": 2, "origin": "refined"},
        {"frame": 35, "type": 1, "origin": "inserted"},
    ],
    "periodic": {"candidates": 6, "removed": [12], "inserted": [35]},
    "repetitions": [
        {"start": 3, "end": 20, "peak": 10, "score": 74.0, "passed": True,
         "guidance": [{"type": "too fast", "frames": [4, 12]}]},
        {"start": 20, "end": 35, "peak": 28, "score": 31.0, "passed": False,
         "guidance": [{"type": "overdone", "frames": [22, 30]}]},
    ],
    "feedback": [{"frame": 20, "text": "Bend your knees more.", "tip": "knees"}],
}  # fmt: skip


@pytest.fixture
def analysed_recording(transactional_db, settings, tmp_path):
    settings.MEDIA_ROOT = tmp_path / "media"
    world = make_world()
    recording = make_recording(world.patient, make_exercise(world.clinic))
    run = recording.runs.first()
    run.status = RunStatus.SUCCEEDED
    run.summary = SUMMARY
    run.arrays.save("run.npz", ContentFile(npz(True)), save=False)
    run.save()
    return recording


def log_in(page, base_url: str) -> None:
    sign_in(page, base_url, "therapist", PASSWORD)


def test_layers_toggle_and_guidance_markers(page, live_server, analysed_recording):
    log_in(page, live_server.url)
    page.goto(f"{live_server.url}/recordings/{analysed_recording.pk}/")
    page.wait_for_selector("#viewer[data-ready='1']")

    layers = {
        "identified": "#timeline .layer[data-layer='identified'] .landmark",
        "refined": "#timeline .layer[data-layer='refined'] .landmark",
        "periodic": "#timeline .layer[data-layer='periodic'] .removed",
    }
    for selector in layers.values():
        assert page.locator(selector).first.is_visible()
    assert page.locator("#timeline .layer[data-layer='periodic'] .inserted").is_visible()

    toggle = page.locator(".timeline-layers input[data-layer='refined']")
    toggle.uncheck()
    assert not page.locator(layers["refined"]).is_visible()
    assert page.locator(layers["identified"]).is_visible()
    toggle.check()
    assert page.locator(layers["refined"]).is_visible()

    markers = page.locator("#timeline .guidance")
    assert markers.count() == 2
    assert markers.nth(0).inner_text() == "too fast"
    assert markers.nth(1).inner_text() == "went too far"
    assert "overdone" not in page.inner_text("body")
    markers.nth(1).click()  # a marker jumps to where its guidance starts
    assert page.evaluate("window.physioPlayback.frame") == 22

    assert "passed (score 74, needs 50)" in page.inner_text("#repetitions")
    assert "not passed (score 31, needs 50)" in page.inner_text("#repetitions")
    assert "did not form a repeating cycle" in page.inner_text("#timeline-fallback")
    page.locator(layers["refined"]).click()
    assert page.evaluate("window.physioPlayback.frame") == 20

    # every figure states its units; joint names are plain words
    svg_text = lambda selector: page.locator(selector).first.text_content()  # noqa: E731
    assert svg_text("#chart-angles .xtitle") == "time (s)"
    assert svg_text("#chart-angles .ytitle") == "angle (°)"
    assert svg_text("#chart-reps .ytitle") == "score (0–100)"
    assert "time (s)" in page.inner_text(".timeline-axis-title")
    legend = svg_text("#chart-angles .legend")
    assert "lower back · your movement" in legend and "Spine" not in legend
