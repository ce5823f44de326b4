"""Live sessions from the therapist's pages in a real browser: the therapist starts a session on
the patient page, the capture client streams into it (``--session``), the home page lists it
while it runs, and its watch page follows the repetitions as they come.

The server is `manage.py runserver` in its own process (WebSockets need the ASGI server), as in
test_live_page.py.
"""

from __future__ import annotations

import subprocess
import sys
import threading
from pathlib import Path

import pytest

from analysis.bvh import read
from bench.bench_live import ROOT, free_port, server_env, setup_world, start_server, stop_server
from capture.remote import run_remote
from capture.sources import Source, header_text, paced
from tests.e2e.conftest import log_in
from tests.personas import FIXTURES, PASSWORD

pytestmark = pytest.mark.e2e
SESSION = FIXTURES / "sessions/m07_s03_incorrect.bvh.gz"
SPEED = 2.5  # times real time: long enough to open the home and watch pages while it runs

PRESCRIBE = """
import sys, django
django.setup()
from django.utils import timezone
from webapp.patients.models import Prescription
Prescription.objects.create(
    patient_id=sys.argv[1], exercise_id=sys.argv[2], start_date=timezone.localdate()
)
"""


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    folder = Path(tmp_path_factory.mktemp("live-dashboard"))
    env = server_env(folder, None)
    world = setup_world(env)
    argv = [sys.executable, "-c", PRESCRIBE, world["patient"], world["exercise"]]
    subprocess.run(argv, env=env, cwd=ROOT, check=True, capture_output=True)
    port = free_port()
    proc = start_server("runserver", env, port, folder / "server.log")
    yield f"http://127.0.0.1:{port}", world
    stop_server(proc)


def stream_in_background(base: str, token: str, session_id: str) -> tuple[threading.Thread, dict]:
    motion = read(SESSION)
    out: dict = {}

    def run() -> None:
        frames = paced(motion.frames, motion.frame_time, SPEED)
        source = Source(header_text(motion), motion.frame_time, frames)
        out["code"] = run_remote(base, token, "", "", source, session=session_id)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread, out


def test_start_on_the_patient_page_then_see_it_under_way_and_watch_it(server, browser, capsys):
    base, world = server
    context = browser.new_context(viewport={"width": 1280, "height": 1000})
    page = context.new_page()
    page.set_default_timeout(60_000)
    try:
        log_in(page, base, "therapist", PASSWORD)

        page.goto(f"{base}/patients/{world['patient']}/")
        page.select_option("#live-exercise", world["exercise"])
        page.click("#start-live")
        page.wait_for_url(lambda url: url.rstrip("/").split("/")[-2] == "live")
        session_id = page.url.rstrip("/").split("/")[-1]
        assert "Waiting for frames" in page.inner_text("#live-state")
        assert f"--session {session_id}" in page.text_content("#capture-help pre")

        thread, out = stream_in_background(base, world["token"], session_id)
        page.goto(f"{base}/")
        row = page.locator(f'#live-under-way tr[data-live="{session_id}"]')
        assert "Ann Example" in row.inner_text() and "Shoulder abduction" in row.inner_text()
        assert row.locator("a", has_text="Ann Example").get_attribute("href") == (
            f"/patients/{world['patient']}/"
        )
        row.locator("a.watch").click()
        page.wait_for_url(f"{base}/live/{session_id}/watch/")
        assert "Watching" in page.inner_text("h1")
        page.wait_for_function("() => document.getElementById('live-state').textContent === 'Live'")
        page.wait_for_function("() => Number(document.getElementById('rep-count').textContent) > 0")
        assert page.locator("#reps tr").count() > 0

        thread.join(timeout=120)
        assert out["code"] == 0
        page.wait_for_function(
            "() => document.getElementById('live-state').textContent === 'Ended'"
        )
        page.goto(f"{base}/")
        assert page.locator(f'#live-under-way tr[data-live="{session_id}"]').count() == 0
        watch = f"Watch this session at {base}/live/{session_id}/watch/"
        assert watch in capsys.readouterr().err.splitlines()
    finally:
        context.close()
