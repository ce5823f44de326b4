"""A live session in a real browser: a capture client streams a UI-PRMD session into the server
(`manage.py runserver`, what `make run` serves, with its in-memory channel layer) while a
therapist watches the live page; the page's counter reaches the offline analysis's count and
guidance is shown.

The server runs in its own process on a throw-away SQLite database (WebSockets need the ASGI
server; pytest-django's live server speaks WSGI only).
"""

from __future__ import annotations

import asyncio
import re
import threading
from pathlib import Path

import pytest

from analysis.bvh import read
from analysis.pipeline import analyse, build_model
from bench.bench_live import (
    create_session,
    free_port,
    server_env,
    setup_world,
    start_server,
    stop_server,
)
from capture.remote import stream_to
from capture.sources import Source, header_text, paced
from tests.e2e.conftest import log_in
from tests.personas import FIXTURES, PASSWORD, fixture_landmarks

pytestmark = pytest.mark.e2e
TUTOR = "sessions/m07_s01_correct.bvh.gz"
SESSION = FIXTURES / "sessions/m07_s03_incorrect.bvh.gz"
SPEED = 6.0  # times real time: 180 frames/s, under the server's rate limit


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    folder = tmp_path_factory.mktemp("live-server")
    env = server_env(Path(folder), None)
    world = setup_world(env)
    port = free_port()
    proc = start_server("runserver", env, port, Path(folder) / "server.log")
    yield f"http://127.0.0.1:{port}", world
    stop_server(proc)


def offline_count() -> int:
    frames, types = fixture_landmarks(TUTOR)
    model = build_model(read(FIXTURES / TUTOR), frames, types)
    return len(analyse(read(SESSION), model).summary.repetitions)


def stream_in_background(url: str, token: str) -> tuple[threading.Thread, dict]:
    motion = read(SESSION)
    out: dict = {}

    def run() -> None:
        frames = paced(motion.frames, motion.frame_time, SPEED)
        source = Source(header_text(motion), motion.frame_time, frames)
        out["summary"] = asyncio.run(stream_to(url, token, source))

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread, out


def test_streamed_session_counts_on_the_live_page(server, browser):
    base, world = server
    expected = offline_count()
    path = create_session(base, world)
    context = browser.new_context(viewport={"width": 1280, "height": 1000})
    page = context.new_page()
    page.set_default_timeout(60_000)
    try:
        log_in(page, base, "therapist", PASSWORD)
        session_id = path.rstrip("/").split("/")[-1]
        page.goto(f"{base}/live/{session_id}/")
        assert "Waiting for frames" in page.inner_text("#live-state")
        page.wait_for_timeout(500)  # the page's WebSocket is open before frames flow

        thread, out = stream_in_background(base.replace("http", "ws") + path, world["token"])
        page.wait_for_function("() => document.getElementById('live-state').textContent === 'Live'")
        page.wait_for_function(
            "() => document.getElementById('guidance').textContent.trim().length > 0"
        )
        # Which repetition's words are on screen depends on how fast the machine is; each is
        # a numbered "well done" or the repetition's first reason (the offline judgement's
        # sentence), never a bare score and never "the tutor".
        guidance = page.inner_text("#guidance")
        assert re.match(r"Repetition \d+: \S", guidance), guidance
        assert "score" not in guidance and "tutor" not in guidance.lower(), guidance
        thread.join(timeout=120)
        assert out["summary"]["repetitions"] == expected
        page.wait_for_function(
            "() => document.getElementById('live-state').textContent === 'Ended'"
        )
        assert int(page.inner_text("#rep-count")) == expected
        assert page.locator("#reps tr").count() == expected
        # praise only where the row says the repetition passed (this take has failed ones)
        said = page.eval_on_selector_all(
            "#reps tr", "rows => rows.map(r => [r.textContent, r.dataset.words])"
        )
        failed = [words for text, words in said if "not passed" in text]
        assert failed and all("well done" not in words for words in failed), said
        assert all(w.startswith("Repetition") for _, w in said)
        assert int(page.inner_text("#errors")) == 0
        assert f"Live: {expected} repetitions" in page.inner_text("#summary")
    finally:
        context.close()
