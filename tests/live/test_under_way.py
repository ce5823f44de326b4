"""A session streamed through the WebSocket (what a capture system does) is on the therapist's
home page while frames arrive, with its repetitions so far, and leaves it when it ends; a
watcher follows it read-only; the capture client names the watch page on stderr."""

from __future__ import annotations

import asyncio

import pytest
from asgiref.sync import async_to_sync
from channels.db import database_sync_to_async
from django.test import Client
from django.utils import timezone

from analysis.__main__ import main
from analysis.bvh import read
from analysis.live import header_text
from capture import remote, stream
from capture.sources import Source
from tests.live.test_consumer import communicator, create_session, until
from tests.personas import FIXTURES
from webapp.accounts.tokens import issue_token
from webapp.live import consumers
from webapp.live.models import LiveSession, LiveStatus
from webapp.live.services import STALE_AFTER

pytestmark = pytest.mark.django_db(transaction=True)


@pytest.fixture(autouse=True)
def _no_queue(monkeypatch):
    monkeypatch.setattr("webapp.recordings.services.enqueue_analysis", lambda run_id: None)
    consumers.SESSIONS.clear()


def logged_in(user) -> Client:
    client = Client()
    client.force_login(user)
    return client


def under_way_row(client: Client, session_id: str) -> str | None:
    """The session's row in the home page's list of sessions under way (None: not listed)."""
    html = client.get("/").content.decode()
    begin = html.index('id="live-under-way"')
    section = html[begin : html.index("</section>", begin)]
    marker = f'data-live="{session_id}"'
    if marker not in section:
        return None
    row = section[section.index(marker) :]
    return row[: row.index("</tr>")]


def test_a_streamed_session_is_listed_while_it_runs_and_watched_read_only(
    world, exercise_with_model, short_recording, settings
):
    settings.LIVE_MAX_FPS = settings.LIVE_BURST = 1e9  # every frame taken, however fast
    key, created = create_session(world.therapist, world.patient, exercise_with_model)
    # opened long ago: only the frames arriving now can put it on the list
    long_ago = timezone.now() - STALE_AFTER * 3
    LiveSession.objects.filter(pk=created["id"]).update(created_at=long_ago)
    assert under_way_row(logged_in(world.colleague), created["id"]) is None
    _, watcher_key = issue_token(world.colleague, "screen")
    motion = read(short_recording)
    home = logged_in(world.colleague)
    listed = database_sync_to_async(under_way_row)

    async def run() -> dict:
        seen: dict = {}
        watcher = communicator(created["ws"] + "?watch=1", watcher_key)
        assert (await watcher.connect())[0]
        sender = communicator(created["ws"], key)
        await sender.connect()
        await sender.send_json_to({"type": "start", "header": header_text(motion)})
        await until(sender, "ready")
        reps = 0
        for seq, values in enumerate(motion.frames):
            await sender.send_json_to({"type": "frame", "seq": seq, "values": values.tolist()})
            if seq == 5:
                seen["early"] = await listed(home, created["id"])
            reps = max(reps, *[e["index"] + 1 for e in await drain(sender, "repetition")], 0)
            if reps >= 1 and "mid" not in seen:
                seen["mid"], seen["mid_reps"] = await listed(home, created["id"]), reps
        seen["watched"] = await until(watcher, "repetition")
        await watcher.send_json_to({"type": "end"})  # a watcher cannot end the session
        seen["refused"] = await until(watcher, "error")
        seen["still"] = await listed(home, created["id"])
        await sender.send_json_to({"type": "end"})
        await until(sender, "summary")
        seen["after"] = await listed(home, created["id"])
        await sender.disconnect()
        await watcher.disconnect()
        return seen

    seen = async_to_sync(run)()
    assert seen["early"] is not None and "Ann Example" in seen["early"]
    assert seen["mid"] is not None and f'<td class="num">{seen["mid_reps"]}</td>' in seen["mid"]
    assert f'href="/live/{created["id"]}/watch/"' in seen["mid"]
    assert seen["watched"][-1]["event"] == "repetition"
    assert any(e["event"] == "position" and "patient" in e for e in seen["watched"])
    assert seen["refused"][-1]["code"] == "read-only" and seen["still"] is not None
    assert seen["after"] is None
    assert LiveSession.objects.get(pk=created["id"]).status == LiveStatus.ENDED


async def drain(comm, kind: str) -> list[dict]:
    """Every event already answered to the connection (none waited for) of the given kind."""
    found = []
    while not await comm.receive_nothing(timeout=0.05):
        event = await comm.receive_json_from()
        events = event if isinstance(event, list) else [event]
        found.extend(e for e in events if e["event"] == kind)
    return found


def test_the_capture_client_names_the_watch_page_on_stderr(monkeypatch, capsys):
    created = {"id": "0b9c5e0e-8f57-4d0f-9a44-5d1c1f0c2a11", "ws": "/ws/live/x/"}
    calls: list = []
    monkeypatch.setattr(remote, "create_session", lambda *args: created)

    async def streamed(url, token, source, batch):
        calls.append(url)
        await asyncio.sleep(0)
        print('{"event": "summary"}')
        return {"event": "summary"}

    monkeypatch.setattr(remote, "stream_to", streamed)
    source = Source("HIERARCHY", 1 / 30, iter(()))
    assert remote.run_remote("http://clinic.example:8000/", "t", "p", "e", source) == 0
    out, err = capsys.readouterr()
    watch = f"Watch this session at http://clinic.example:8000/live/{created['id']}/watch/"
    assert err.splitlines() == [watch]
    assert out == '{"event": "summary"}\n'  # stdout keeps only the JSON lines
    assert calls == ["ws://clinic.example:8000/ws/live/x/"]
    remote.run_remote("http://clinic.example:8000", "t", "", "", source, session="abc")
    assert capsys.readouterr().err.strip().endswith("/live/abc/watch/")
    assert calls[-1] == "ws://clinic.example:8000/ws/live/abc/"


def test_session_flag_streams_into_a_started_session_without_patient_or_exercise(monkeypatch):
    joined: list = []
    monkeypatch.setattr(stream, "run_remote", lambda *a, **kw: joined.append(kw["session"]) or 0)
    recording = str(FIXTURES / "sessions/m07_s03_incorrect.bvh.gz")
    argv = ["stream", recording, "--server", "http://h:1", "--token", "t", "--json-lines"]
    assert main([*argv, "--session", "abc"]) == 0 and joined == ["abc"]
    assert main(argv) == 2 and joined == ["abc"]  # no session: --patient and --exercise needed
