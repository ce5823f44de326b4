"""Live frames in binary form (float32, `analysis.live.frames`): the codec, malformed messages,
the real consumer answering binary frames as it answers the same frames in JSON, and the
capture client sending binary only to a server that reads it."""

from __future__ import annotations

import asyncio
import json
import struct

import numpy as np
import pytest
from asgiref.sync import async_to_sync

from analysis.bvh import read
from analysis.live import LiveSession, ProtocolError, header_text
from analysis.live.frames import decode_frames, encode_frames, take_frames
from capture.sources import Source
from tests.live.test_consumer import communicator, create_session
from webapp.live import consumers
from webapp.recordings.models import Recording

MEASURED = ("latency_ms", "cpu_ms", "latency_ms_p95", "recording")  # not the same twice


@pytest.fixture(autouse=True)
def _no_queue(monkeypatch):
    """The stored recording's analysis is the pipeline's business, tested elsewhere."""
    monkeypatch.setattr("webapp.recordings.services.enqueue_analysis", lambda run_id: None)
    consumers.SESSIONS.clear()


def float32(frames: np.ndarray) -> np.ndarray:
    """The values as binary frames carry them."""
    return frames.astype(np.float32).astype(np.float64)


def test_codec_round_trip_keeps_seq_shape_and_float32_values():
    rng = np.random.default_rng(0)
    frames = rng.normal(0.0, 90.0, (3, 69))
    data = encode_frames(1234, frames)
    assert len(data) == 12 + 4 * 3 * 69 and data[:4] == b"LVF\x01"
    block = decode_frames(data)
    assert block.seq == 1234 and block.values.shape == (3, 69)
    assert np.array_equal(block.values, float32(frames))
    assert np.abs(block.values - frames).max() < 1e-4  # float32: 7 significant digits
    one = decode_frames(encode_frames(0, frames[0]))  # one frame, (C,)
    assert one.values.shape == (1, 69) and np.array_equal(one.values[0], float32(frames[0]))


@pytest.mark.parametrize("frames", [np.zeros((0, 5)), np.zeros((65, 5)), np.zeros((2, 0))])
def test_encoding_refuses_what_the_format_cannot_hold(frames):
    with pytest.raises(ValueError, match="1 to 64 frames"):
        encode_frames(0, frames)


GOOD = encode_frames(7, np.ones((2, 4)))
MALFORMED = {
    "empty": b"",
    "short header": GOOD[:11],
    "magic": b"XYZ" + GOOD[3:],
    "version": GOOD[:3] + b"\x02" + GOOD[4:],
    "no frames": GOOD[:4] + struct.pack("<HHI", 0, 4, 7),
    "no values": GOOD[:4] + struct.pack("<HHI", 2, 0, 7),
    "too many frames": GOOD[:4] + struct.pack("<HHI", 65, 4, 7) + bytes(65 * 16),
    "truncated": GOOD[:-1],
    "extra bytes": GOOD + b"\x00\x00\x00\x00",
}


@pytest.mark.parametrize("name", MALFORMED)
def test_a_malformed_message_is_refused_saying_why(name):
    with pytest.raises(ProtocolError) as refused:
        decode_frames(MALFORMED[name])
    assert refused.value.code == "bad-binary" and len(str(refused.value)) > 20


def events_of(answer) -> list[dict]:
    return answer if isinstance(answer, list) else [answer]


async def collect_until_summary(comm) -> list[dict]:
    events: list[dict] = []
    while not events or events[-1]["event"] != "summary":
        events += events_of(await comm.receive_json_from(timeout=30))
    return events


async def stream_batches(path: str, key: str, motion, frames: np.ndarray, binary: bool):
    """Start, the frames three to a message (binary or JSON), end: the ready event and every
    event after it."""
    comm = communicator(path, key)
    assert (await comm.connect())[0]
    await comm.send_json_to({"type": "start", "header": header_text(motion)})
    ready = await comm.receive_json_from(timeout=30)
    for first in range(0, len(frames), 3):
        part = frames[first : first + 3]
        if binary:
            await comm.send_to(bytes_data=encode_frames(first, part))
        else:
            await comm.send_json_to({"type": "frames", "seq": first, "frames": part.tolist()})
    await comm.send_json_to({"type": "end"})
    events = await collect_until_summary(comm)
    await comm.disconnect()
    return ready, events


@pytest.mark.django_db(transaction=True)
def test_binary_frames_give_the_events_the_same_frames_in_json_give(
    world, exercise_with_model, short_recording, settings
):
    settings.LIVE_MAX_FPS = settings.LIVE_BURST = 1e9  # every frame taken, however fast
    motion = read(short_recording)
    frames = float32(motion.frames)  # both sessions get exactly the same numbers
    answers = {}
    for form in ("json", "binary"):
        key, created = create_session(world.therapist, world.patient, exercise_with_model)
        answers[form] = async_to_sync(stream_batches)(
            created["ws"], key, motion, frames, form == "binary"
        )
    (ready, binary), (_, json_events) = answers["binary"], answers["json"]
    assert ready["event"] == "ready" and ready["binary_frames"] == 1

    def strip(events: list[dict]) -> list[dict]:
        return [{k: v for k, v in e.items() if k not in MEASURED} for e in events]

    assert strip(binary) == strip(json_events)
    kinds = [e["event"] for e in binary]
    assert kinds.count("position") >= 250 // 10 and kinds.count("repetition") >= 2
    assert "error" not in kinds and binary[-1]["frames"] == 250
    stored = Recording.objects.get(pk=binary[-1]["recording"])
    assert stored.n_frames == 250


@pytest.mark.django_db(transaction=True)
def test_bad_binary_messages_get_errors_and_the_session_goes_on(
    world, exercise_with_model, short_recording, settings
):
    settings.LIVE_MAX_FPS = settings.LIVE_BURST = 1e9
    key, created = create_session(world.therapist, world.patient, exercise_with_model)
    motion = read(short_recording)
    frames = motion.frames[:8]
    with_nan = frames[3:6].copy()
    with_nan[1, 2] = np.nan

    async def run() -> list:
        comm = communicator(created["ws"], key)
        await comm.connect()
        answers = []
        await comm.send_to(bytes_data=encode_frames(0, frames[:3]))  # before start
        answers.append(await comm.receive_json_from(timeout=10))
        await comm.send_json_to({"type": "start", "header": header_text(motion)})
        await comm.receive_json_from(timeout=30)
        for data in (
            b"\x00\x01binary",
            encode_frames(0, frames[:3])[:-2],
            encode_frames(0, frames[:3, :-1]),  # a value short in every frame
            encode_frames(0, frames[:3]),
            encode_frames(9, frames[6:8]),  # after the next expected frame
            encode_frames(3, with_nan),
            encode_frames(5, frames[5:8]),  # 5 used up by the bad frame: a repeat
        ):
            await comm.send_to(bytes_data=data)
            answers.append(await comm.receive_json_from(timeout=30))
        await comm.disconnect()
        return answers

    before, magic, cut, count, good, ahead, nan, again = async_to_sync(run)()
    assert [e["code"] for e in before] == ["not-started"]
    for refused in (magic, cut):
        assert refused["event"] == "error" and refused["code"] == "bad-binary"
        assert refused["message"]
    assert [(e["code"], e["seq"]) for e in count] == [("value-count", 0)]
    assert [e["frame"] for e in good] == [0, 1, 2] and good[0]["latency_ms"] >= 0
    assert [(e["code"], e["seq"]) for e in ahead] == [("out-of-order", 9)]
    # a position's frame counts the frames taken: seq 5 is the fifth taken (4 was refused)
    answered = [(e["event"], e.get("seq", e.get("frame"))) for e in nan]
    assert answered == [("position", 3), ("error", 4), ("position", 4)]
    assert nan[1]["code"] == "not-finite"
    assert [e.get("code") for e in again] == ["duplicate", None, None]
    assert [e["frame"] for e in again[1:]] == [5, 6]
    state = consumers.SESSIONS[created["id"]]
    assert state.next_seq == 8 and len(state.frames) == 7  # frame 4 used up its number


def stream_to_a_fake_server(session: LiveSession, motion, announce: bool) -> tuple[dict, list]:
    """`capture.remote.stream_to` against a server answering with ``session`` whose ``ready``
    says it reads binary frames (``announce``) or not (an older server); the summary and the
    form of every frame message it read."""
    from websockets.asyncio.server import serve

    from capture.remote import stream_to

    forms: list[str] = []

    async def handler(ws) -> None:
        async for raw in ws:
            if isinstance(raw, bytes):
                forms.append("binary")
                events = take_frames(session, decode_frames(raw))
            else:
                message = json.loads(raw)
                forms.append(message["type"])
                events = session.handle(message)
            for event in events:
                if event["event"] == "ready" and announce:
                    event["binary_frames"] = 1
            if forms[-1] in ("binary", "frames"):  # a batch's events in one message
                await ws.send(json.dumps(events))
            else:
                for event in events:
                    await ws.send(json.dumps(event))

    async def run() -> dict:
        async with serve(handler, "127.0.0.1", 0) as server:
            port = server.sockets[0].getsockname()[1]
            source = Source(header_text(motion), motion.frame_time, iter(motion.frames))
            return await stream_to(f"ws://127.0.0.1:{port}/", "token", source, batch=3)

    return asyncio.run(run()), forms


@pytest.mark.parametrize("announce", [True, False])
def test_the_client_sends_binary_only_to_a_server_that_reads_it(
    live_model, short_recording, announce, capsys
):
    motion = read(short_recording)
    session = LiveSession(live_model, max_fps=1e9, burst=1e9)
    summary, forms = stream_to_a_fake_server(session, motion, announce)
    assert summary["frames"] == motion.n_frames
    frame_forms = set(forms) - {"start", "end"}
    assert frame_forms == {"binary"} if announce else frame_forms <= {"frame", "frames"}
    held = np.vstack(session.frames)
    assert np.array_equal(held, float32(motion.frames) if announce else motion.frames)
    printed = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert printed[-1]["event"] == "summary"
    assert sum(e["event"] == "position" for e in printed) >= motion.n_frames // 10
