"""Live sessions without a server: ``python -m analysis stream --model``, the session protocol,
streaming GB-DTW, the TCP relay and the WebSocket client's resume after a dropped connection."""

from __future__ import annotations

import asyncio
import gzip
import json
import socket
import threading
from pathlib import Path

import numpy as np
import pytest

from analysis.__main__ import main
from analysis.bvh import read
from analysis.live import LiveSession, RateLimit
from analysis.pipeline import analyse, build_model, dump_model
from capture.stream import Source, header_text

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
TUTOR = "sessions/m07_s01_correct.bvh.gz"
SESSION = DATA / "sessions/m07_s03_incorrect.bvh.gz"


def landmarks(relative: str) -> tuple[list[int], list[int]]:
    for line in (DATA / "landmarks.csv").read_text().splitlines():
        if line.startswith(relative):
            _, frames, types = line.split(",")
            return [int(v) for v in frames.split(";")], [int(v) for v in types.split(";")]
    raise LookupError(relative)


@pytest.fixture(scope="module")
def model():
    return build_model(read(DATA / TUTOR), *landmarks(TUTOR))


@pytest.fixture(scope="module")
def model_path(model, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("model") / "m07.model"
    with out.open("wb") as handle:
        dump_model(model, handle)
    return out


def events_of(text: str) -> list[dict]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


@pytest.mark.parametrize("exercise", ["m07", "m08"])
def test_stream_counts_the_offline_repetitions(exercise, model, model_path, tmp_path, capsys):
    """m07: shoulder abduction; m08: shoulder extension by a patient twice slower than the tutor."""
    session, path = SESSION, model_path
    if exercise != "m07":
        tutor = f"sessions/{exercise}_s01_correct.bvh.gz"
        model = build_model(read(DATA / tutor), *landmarks(tutor))
        path, session = tmp_path / "model", DATA / f"sessions/{exercise}_s02_correct.bvh.gz"
        with path.open("wb") as handle:
            dump_model(model, handle)
    capsys.readouterr()
    code = main(["stream", "--model", str(path), str(session), "--speed", "max", "--json-lines"])
    assert code == 0
    events = events_of(capsys.readouterr().out)
    offline = len(analyse(read(session), model).summary.repetitions)
    reps = [e for e in events if e["event"] == "repetition"]
    assert abs(len(reps) - offline) <= 1
    assert [r["index"] for r in reps] == list(range(len(reps)))
    assert all(0 <= r["score"] <= 100 and isinstance(r["guidance"], list) for r in reps)
    frames = [e["frame"] for e in events if e["event"] == "position"]
    assert frames[0] < 10 and np.diff(frames).max() <= 10
    summary = events[-1]
    assert summary["event"] == "summary" and summary["repetitions"] == len(reps)
    assert summary["frames"] == read(session).n_frames and summary["recording"] is None
    assert summary["latency_ms_p95"] > 0


def test_tutor_playback_never_goes_back_within_a_repetition(model, model_path, capsys):
    """One repetition: the playback only moves forward until the repetition is counted, then
    starts the tutor's movement again for the next one."""
    capsys.readouterr()
    main(["stream", "--model", str(model_path), str(DATA / "reps/m07_s01_e02.bvh.gz"),
          "--speed", "max", "--json-lines"])  # fmt: skip
    events = events_of(capsys.readouterr().out)
    counted = next(k for k, e in enumerate(events) if e["event"] == "repetition")
    tutor = [e["tutor_frame"] for e in events[:counted] if e["event"] == "position"]
    assert np.all(np.diff(tutor) >= 0) and tutor[-1] - tutor[0] > 40
    after = [e["tutor_frame"] for e in events[counted:] if e["event"] == "position"]
    assert after[0] < tutor[-1] and np.all(np.diff(after) >= 0)


def test_bad_input_exits_2_with_one_line(model_path, tmp_path, capsys):
    truncated = tmp_path / "t.bvh"
    text = gzip.decompress((DATA / "reps/m07_s01_e01.bvh.gz").read_bytes()).decode()
    truncated.write_text(text[: len(text) // 3])
    cases = [
        ["stream", "--model", str(model_path), str(truncated), "--json-lines"],
        ["stream", "--model", str(model_path), str(tmp_path / "missing.bvh")],
        ["stream", "--model", str(model_path), str(SESSION), "--speed", "fast"],
        ["stream", str(SESSION), "--server", "http://127.0.0.1:9", "--token", "t"],
        ["stream", str(SESSION)],
    ]
    for argv in cases:
        capsys.readouterr()
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.startswith("error:") and err.count("\n") == 1, err


def test_refused_token_exits_2(tmp_path, capsys, monkeypatch):
    import urllib.error
    import urllib.request

    def refuse(*args, **kwargs):
        raise urllib.error.HTTPError("u", 401, "Unauthorized", {}, None)  # type: ignore[arg-type]

    monkeypatch.setattr(urllib.request, "urlopen", refuse)
    argv = ["stream", str(SESSION), "--server", "http://127.0.0.1:8000", "--token", "bad",
            "--patient", "p", "--exercise", "e", "--json-lines"]  # fmt: skip
    assert main(argv) == 2
    assert "refused the token" in capsys.readouterr().err


def start_message(path: Path) -> tuple[dict, np.ndarray]:
    motion = read(path)
    return {"type": "start", "header": header_text(motion)}, motion.frames


def test_session_answers_each_bad_frame_with_an_error_and_goes_on(model):
    session = LiveSession(model)
    start, frames = start_message(DATA / "reps/m07_s01_e02.bvh.gz")
    assert session.handle({"type": "frame", "seq": 0, "values": []})[0]["code"] == "not-started"
    assert session.handle(start)[0] == {"event": "ready", "next_seq": 0, "max_fps": 1000.0,
                                        "started": True}  # fmt: skip
    good = frames[0].tolist()
    assert session.handle({"type": "frame", "seq": 0, "values": good})[-1]["event"] == "position"
    bad = {
        "value-count": {"seq": 1, "values": good[:-2]},
        "not-finite": {"seq": 1, "values": [float("inf"), *good[1:]]},
        "not-a-number": {"seq": 1, "line": "a " * len(good)},
        "out-of-order": {"seq": 7, "values": good},
        "duplicate": {"seq": 0, "values": good},
        "bad-frame": {"seq": 1},
    }
    for code, message in bad.items():
        answer = session.handle({"type": "frame", **message})
        assert answer == [{"event": "error", "code": code, "message": answer[0]["message"],
                           "seq": answer[0]["seq"]}], code  # fmt: skip
    line = " ".join(map(str, frames[1]))
    assert session.handle({"type": "frame", "seq": 1, "line": line})[-1]["frame"] == 1
    summary = session.end()[-1]
    assert summary["frames"] == 2 and summary["errors"] == len(bad) + 1
    assert read(session.bvh().encode()).n_frames == 2


def test_rate_limit_drops_a_flood():
    now = [0.0]
    limit = RateLimit(rate=10.0, burst=5.0, clock=lambda: now[0])
    assert sum(limit.allow() for _ in range(50)) == 5  # the burst, then nothing at t = 0
    now[0] = 1.0
    assert sum(limit.allow() for _ in range(50)) == 5  # refilled to the burst, no more


def test_tcp_relay_of_frame_lines(model_path, capsys):
    path = DATA / "reps/m07_s01_e02.bvh.gz"
    frames = read(path).frames
    server = socket.create_server(("127.0.0.1", 0))

    def serve() -> None:
        conn, _ = server.accept()
        with conn:
            conn.sendall(b"keep-alive\n")
            for row in frames:
                conn.sendall((" ".join(f"{v:.4f}" for v in row) + "\n").encode())

    threading.Thread(target=serve, daemon=True).start()
    port = server.getsockname()[1]
    capsys.readouterr()
    argv = ["stream", "--model", str(model_path), "--tcp", f"127.0.0.1:{port}",
            "--header", str(path), "--json-lines"]  # fmt: skip
    assert main(argv) == 0
    server.close()
    assert events_of(capsys.readouterr().out)[-1]["frames"] == len(frames)


def stream_through_a_dropping_server(session: LiveSession, motion, batch: int | None = None):
    """Stream ``motion`` with `stream_to` to a fake server that answers with ``session`` and drops
    the first connection once it holds 30 frames; returns the client's summary, the connections
    and the type of every message the server read."""
    from websockets.asyncio.server import serve

    from capture.remote import stream_to

    connections, kinds = [], []

    async def handler(ws) -> None:
        connections.append(ws)
        async for raw in ws:
            message = json.loads(raw)
            kinds.append(message["type"])
            events = session.handle(message)
            if message["type"] == "frames" and events:
                await ws.send(json.dumps(events))  # a batch's events in one message
            else:
                for event in events:
                    await ws.send(json.dumps(event))
            if len(connections) == 1 and session.next_seq >= 30:
                await ws.close()
                return

    async def run() -> dict:
        async with serve(handler, "127.0.0.1", 0) as server:
            port = server.sockets[0].getsockname()[1]
            source = Source(header_text(motion), motion.frame_time, iter(motion.frames))
            return await stream_to(f"ws://127.0.0.1:{port}/", "token", source, batch=batch)

    return asyncio.run(run()), connections, kinds


def test_client_resumes_after_a_dropped_connection(model, capsys):
    """A fake server that drops the first connection after 30 frames: nothing is lost."""
    motion = read(DATA / "reps/m07_s01_e02.bvh.gz")
    session = LiveSession(model)
    summary, connections, _ = stream_through_a_dropping_server(session, motion)
    assert len(connections) == 2
    assert summary["frames"] == motion.n_frames
    assert np.array_equal(np.vstack(session.frames), motion.frames)


TIMINGS = ("latency_ms", "cpu_ms")  # measured, so not the same twice


def test_a_batch_is_taken_as_its_frames_one_by_one(model):
    start, frames = start_message(DATA / "reps/m07_s01_e02.bvh.gz")
    single, batched = LiveSession(model), LiveSession(model)
    single.handle(start), batched.handle(start)
    one = [e for seq, v in enumerate(frames) for e in single.handle(
        {"type": "frame", "seq": seq, "values": v.tolist()})]  # fmt: skip
    many = []
    for first in range(0, len(frames), 3):
        part = [v.tolist() for v in frames[first : first + 3]]
        if first == 3:  # a frame as a BVH line is taken too
            part[0] = " ".join(map(str, part[0]))
        many += batched.handle({"type": "frames", "seq": first, "frames": part})
    strip = [{k: v for k, v in e.items() if k not in TIMINGS} for e in one]
    assert [{k: v for k, v in e.items() if k not in TIMINGS} for e in many] == strip
    assert any(e["event"] == "position" for e in many)
    assert batched.next_seq == len(frames) and np.array_equal(
        np.vstack(batched.frames), np.vstack(single.frames)
    )


def test_a_bad_frame_of_a_batch_gets_its_error_and_the_rest_are_taken(model):
    session = LiveSession(model)
    start, frames = start_message(DATA / "reps/m07_s01_e02.bvh.gz")
    session.handle(start)
    good = [v.tolist() for v in frames[:8]]
    session.handle({"type": "frames", "seq": 0, "frames": good[:4]})
    batch = [good[4], [float("nan"), *good[5][1:]], good[6][:-1], good[7]]
    events = session.handle({"type": "frames", "seq": 4, "frames": batch})
    errors = [e for e in events if e["event"] == "error"]
    assert [(e["code"], e["seq"]) for e in errors] == [("not-finite", 5), ("value-count", 6)]
    assert len(session.frames) == 6 and session.next_seq == 8  # 5 and 6 used up, 7 taken
    assert np.array_equal(session.frames[-1], frames[7])
    after = session.handle({"type": "frame", "seq": 8, "values": frames[8].tolist()})
    assert not [e for e in after if e["event"] == "error"]
    assert session.end()[-1]["errors"] == 2


def test_an_out_of_order_batch_is_refused_and_a_resent_one_skips_what_was_taken(model):
    session = LiveSession(model)
    start, frames = start_message(DATA / "reps/m07_s01_e02.bvh.gz")
    session.handle(start)
    values = [v.tolist() for v in frames[:10]]
    session.handle({"type": "frames", "seq": 0, "frames": values[:3]})
    ahead = session.handle({"type": "frames", "seq": 5, "frames": values[5:8]})
    assert [(e["code"], e["seq"]) for e in ahead] == [("out-of-order", 5)]
    assert session.next_seq == 3
    again = session.handle({"type": "frames", "seq": 1, "frames": values[1:6]})
    assert [(e["code"], e["seq"]) for e in again if e["event"] == "error"] == [("duplicate", 1)]
    assert session.next_seq == 6 and np.array_equal(np.vstack(session.frames), frames[:6])
    for bad in ({"seq": 6, "frames": []}, {"seq": 6, "frames": "x"}, {"frames": [values[6]]}):
        (answer,) = session.handle({"type": "frames", **bad})
        assert answer["code"] in ("bad-frame", "bad-seq")
    assert session.next_seq == 6


def test_default_batch_adds_at_most_25_ms():
    from capture.remote import default_batch

    assert [default_batch(1 / fps) for fps in (30, 60, 120, 240)] == [1, 1, 3, 6]
    assert all((default_batch(1 / fps) - 1) / fps <= 0.025 for fps in (30, 100, 120, 480))


def test_client_sends_batches_and_resumes_after_a_dropped_connection(model, capsys):
    motion = read(DATA / "reps/m07_s01_e02.bvh.gz")
    session = LiveSession(model)
    summary, connections, kinds = stream_through_a_dropping_server(session, motion, batch=4)
    assert len(connections) == 2 and kinds.count("frames") >= motion.n_frames // 4 - 2
    assert summary["frames"] == motion.n_frames
    assert np.array_equal(np.vstack(session.frames), motion.frames)
    printed = events_of(capsys.readouterr().out)
    frames = [e["frame"] for e in printed if e["event"] == "position"]
    assert frames == sorted(set(frames))  # each position once, in order


def test_live_guidance_is_the_offline_pipelines_rule(model):
    """Each live repetition gets the guidance the offline pipeline's gesture stage gives the same
    frames (Table 1 on the WOOE-DTW alignment with a tutor repetition), not a rule of its own:
    the stage run on the whole recording with the live repetitions' spans says the same, though
    the live side computed it frame by frame from the stream. Both are told the same earlier
    session's pace (slower and farther than this take), so there is guidance to compare."""
    from analysis.landmarks.segmentation import Segments
    from analysis.live import LiveAligner, LiveOptions
    from analysis.pipeline.gestures import Pace
    from analysis.pipeline.prepare import prepare, progress_signal
    from analysis.pipeline.repetition_stage import Synchronised, gesture_results

    motion = read(SESSION)
    earlier = Pace(tempo=1.8, reach=1.2, earlier=True)
    aligner = LiveAligner(model, motion.skeleton, motion.fps, LiveOptions(own_pace=earlier))
    for values in motion.frames:
        aligner.push(values)
    aligner.finish()
    reps = aligner.repetitions
    live = [[g["type"] for g in r["guidance"]] for r in reps]
    assert model.fps == motion.fps, "stream frames are the model's frames here"

    parts = model.components
    prepared = prepare(motion, model.tutor.skeleton, model.fps, parts.axis.rep_frames)
    progress, _ = progress_signal(prepared, parts.axis, parts.mirror)
    spans = Segments(*(np.array([r[k] for r in reps]) for k in ("start", "end", "end")))
    offline = gesture_results(prepared, spans, progress, Synchronised({}, None), model, own=earlier)
    assert live == [[g.type for g in result.guidance] for result in offline]
    assert any(live), "the session needs guidance for the test to say anything"
    assert all(g["text"] for r in reps for g in r["guidance"]), "words for the patient"
