"""The camera page in a real browser, the camera being Chromium's fake one fed from a clip:

- the phone video of two squats (tests/analysis/fixtures/capture), turned into a `.y4m` clip
  (the still start and the racking of the bar left out) and slowed so that the pose engine
  keeps up on the software renderer: the patient opens the
  demo's deep squat with the camera, starts, stops at the clip's end; the page counts 2, the
  session is saved and analysed with the patient's recordings; no request leaves the site;
  axe-core finds no serious violation; the page fits a 390 px phone;
- a clip of an empty room: the page says no one is in view and counts nothing.

The site runs as `make run` runs it (`tests/local_server.py`: ASGI server for the WebSocket and a
real worker), on the demo clinic.
"""

from __future__ import annotations

import re
import time
from pathlib import Path

import pytest

from tests.e2e.conftest import CHROMIUM, log_in
from tests.e2e.test_patient_phone import serious_violations
from tests.live.camera_clips import empty_room_clip, squat_clip
from tests.local_server import LocalServer

pytestmark = pytest.mark.e2e
PHONE = {"width": 390, "height": 844}
SLOWER = 1.5  # the clip plays this many times slower than it was filmed
# The part of the video played: 4 s of standing before the first squat (a loop back to its start
# is standing too) to the end of the second, before the bar is racked: what is left out holds
# no squat.
FILMED = (5.0, 19.0)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    with LocalServer(tmp_path_factory.mktemp("camera-site"), demo=True) as server:
        yield server


def camera_browser(clip: Path):
    from playwright.sync_api import sync_playwright

    playwright = sync_playwright().start()
    browser = playwright.chromium.launch(
        executable_path=str(CHROMIUM),
        headless=True,
        args=[
            "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
            "--use-fake-ui-for-media-stream", "--use-fake-device-for-media-stream",
            f"--use-file-for-fake-video-capture={clip}",
        ],
    )  # fmt: skip
    return playwright, browser


def open_camera_page(browser, site, hosts: set[str]):
    context = browser.new_context(viewport=PHONE)
    context.on("request", lambda request: hosts.add(request.url.split("/")[2]))
    page = context.new_page()
    page.set_default_timeout(60_000)
    log_in(page, site.url, "demo-patient")
    page.goto(site.url + "/")
    item = page.locator(".plan-item", has_text="Deep squat")
    item.locator("a.camera-link").click()
    page.wait_for_url("**/my/live/camera/*/")
    return context, page


def state(page) -> str:
    return page.get_attribute("[data-live-state]", "data-live-state")


def count(page) -> int:
    return int(page.inner_text("[data-live-count]"))


def test_two_squats_in_front_of_the_camera(site, tmp_path):
    clip, seconds = squat_clip(tmp_path / "squat.y4m", slower=SLOWER, between=FILMED)
    playwright, browser = camera_browser(clip)
    hosts: set[str] = set()
    try:
        context, page = open_camera_page(browser, site, hosts)
        assert "never leave this device" in page.inner_text("#camera-privacy")
        assert state(page) == "waiting" and count(page) == 0
        started = time.monotonic()  # the page opens the camera at once
        page.click("#camera-start")
        page.wait_for_function(
            "document.querySelector('[data-live-state]').dataset.liveState === 'running'"
        )
        # the fake camera plays the clip from its start when the page opens it, then loops
        page.wait_for_timeout(max(0.0, seconds + 1.0 - (time.monotonic() - started)) * 1000)
        page.click("#camera-stop")
        page.wait_for_function(
            "document.querySelector('[data-live-state]').dataset.liveState === 'ended'",
            timeout=90_000,
        )
        words = page.locator("#camera-reps li").all_inner_texts()
        assert count(page) == 2, (words, page.inner_text("#camera-message"))
        assert len(words) == 2 and all(w.strip() for w in words)
        assert "tutor" not in page.inner_text("#camera").lower()
        assert page.evaluate("document.documentElement.scrollWidth") <= PHONE["width"]
        assert serious_violations(page) == []
        page.click("#camera-summary a")  # the session is one of the patient's recordings
        page.wait_for_url("**/recordings/*/")
        # the saved landmarks, analysed against the same exercise, count the same two squats
        assert analysed_count(page) == 2
        assert hosts == {site.url.split("/")[2]}, hosts  # no request left the site
        context.close()
    finally:
        browser.close()
        playwright.stop()


def analysed_count(page) -> int:
    """The repetitions the patient's page of the recording says, once its analysis is done."""
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        found = re.search(r"How it went\s+(\d+)\s+repetitions? done", page.inner_text("main"))
        if found:
            return int(found.group(1))
        page.wait_for_timeout(2000)
        page.reload()
    raise AssertionError(page.inner_text("main")[:2000])


def test_an_empty_room_counts_nothing(site, tmp_path):
    clip = empty_room_clip(tmp_path / "room.y4m")
    playwright, browser = camera_browser(clip)
    hosts: set[str] = set()
    try:
        context, page = open_camera_page(browser, site, hosts)
        page.click("#camera-start")
        page.wait_for_function(
            "document.getElementById('camera-message').dataset.reason === 'nobody'"
        )
        assert "No one is in view" in page.inner_text("#camera-message")
        page.wait_for_timeout(2000)
        assert count(page) == 0
        page.click("#camera-stop")
        page.wait_for_function(
            "document.querySelector('[data-live-state]').dataset.liveState === 'ended'"
        )
        assert count(page) == 0
        context.close()
    finally:
        browser.close()
        playwright.stop()
