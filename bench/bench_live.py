"""Latency of live sessions: frame received → position event sent, at 120 frames/s.

1. Server path: the real ASGI application (Channels consumer, token authentication, the per-session
   aligner, the channel-layer broadcast to viewers) driven in-process by a WebSocket client that
   sends a UI-PRMD session's frames at 120 frames/s (its 30 fps frames four times faster, so every
   frame is aligned); the consumer measures receive → send per position event. Also the
   client-side round trip (send → position event received).
2. In-process aligner (``python -m analysis stream --model``): per-frame processing time.

Uses a throw-away in-memory SQLite database.

    python -m bench.bench_live [--fps 120] [--session sessions/m07_s03_incorrect.bvh.gz]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import platform
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1] / "data" / "ui-prmd"
TUTOR = "sessions/m07_s01_correct.bvh.gz"


def build():
    from analysis.bvh import read
    from analysis.pipeline import build_model

    for line in (DATA / "landmarks.csv").read_text().splitlines():
        if line.startswith(TUTOR):
            _, frames, types = line.split(",")
            return build_model(
                read(DATA / TUTOR),
                [int(v) for v in frames.split(";")],
                [int(v) for v in types.split(";")],
            )
    raise LookupError(TUTOR)


def world(model):
    """A clinic, a therapist with a token, a patient, the exercise and an open live session."""
    from tests.personas import make_exercise, make_world
    from webapp.accounts.tokens import issue_token
    from webapp.live import services

    w = make_world()
    exercise = make_exercise(w.clinic, "Shoulder abduction", TUTOR)
    services.exercise_model = lambda _exercise: model
    _, key = issue_token(w.therapist, "bench")
    live = services.create_session(patient=w.patient, exercise=exercise, user=w.therapist)
    return key, live.ws_path


async def drive(path: str, key: str, frames: np.ndarray, header: str, fps: float) -> dict:
    from channels.testing import WebsocketCommunicator

    from webapp.asgi import application

    comm = WebsocketCommunicator(
        application, path, headers=[(b"authorization", f"Token {key}".encode())]
    )
    assert (await comm.connect())[0]
    await comm.send_json_to({"type": "start", "header": header})
    await comm.receive_json_from(timeout=60)
    sent: dict[int, float] = {}
    trips: list[float] = []
    server: list[float] = []

    async def receive() -> dict:
        while True:
            event = await comm.receive_json_from(timeout=60)
            if event["event"] == "position":
                trips.append((time.perf_counter() - sent[event["frame"]]) * 1000.0)
                server.append(event["latency_ms"])
            if event["event"] == "summary":
                return event

    reader = asyncio.create_task(receive())
    start = time.perf_counter()
    for seq, values in enumerate(frames):
        await asyncio.sleep(max(0.0, start + seq / fps - time.perf_counter()))
        sent[seq] = time.perf_counter()
        await comm.send_json_to({"type": "frame", "seq": seq, "values": values.tolist()})
    await comm.send_json_to({"type": "end"})
    summary = await reader
    await comm.disconnect()
    return {"summary": summary, "trips": trips, "server": server}


def server_path(model, session: Path, fps: float) -> dict:
    import django
    from django.db import connection

    from analysis.bvh import read
    from analysis.online.stream import header_text

    os.environ.setdefault("DJANGO_SETTINGS_MODULE", "webapp.settings")
    django.setup()
    from django.conf import settings

    settings.MEDIA_ROOT = str(Path("/tmp") / f"bench-live-{os.getpid()}")
    import webapp.recordings.services as queue

    queue.enqueue_analysis = lambda run_id: None  # the offline analysis is not measured here
    old = connection.creation.create_test_db(verbosity=0, autoclobber=True)
    try:
        key, path = world(model)
        motion = read(session)
        return asyncio.run(drive(path, key, motion.frames, header_text(motion), fps))
    finally:
        connection.creation.destroy_test_db(old, verbosity=0)


def in_process(model, session: Path) -> list[float]:
    from analysis.bvh import read
    from analysis.online.live import LiveAligner

    motion = read(session)
    aligner = LiveAligner(model, motion.skeleton, motion.fps)
    for values in motion.frames:
        aligner.push(values)
    return aligner.latencies_ms


def p(values: list[float], q: float) -> float:
    return round(float(np.percentile(values, q)), 2)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--fps", type=float, default=120.0)
    parser.add_argument("--session", default="sessions/m07_s03_incorrect.bvh.gz")
    args = parser.parse_args()
    session = DATA / args.session
    model = build()
    in_process(model, session)  # warm-up: numba kernels compile once
    local = in_process(model, session)
    result = server_path(model, session, args.fps)
    s = result["summary"]
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"Python {platform.python_version()}")  # fmt: skip
    print(f"session {args.session}: {s['frames']} frames sent at {args.fps:g} frames/s, "
          f"{s['repetitions']} repetitions, {s.get('dropped', 0)} dropped")  # fmt: skip
    print(
        f"server, frame received -> position sent: p50 {p(result['server'], 50)} ms, "
        f"p95 {p(result['server'], 95)} ms (summary latency_ms_p95 {s['latency_ms_p95']})"
    )
    print(f"client round trip (send -> position received): p50 {p(result['trips'], 50)} ms, "
          f"p95 {p(result['trips'], 95)} ms")  # fmt: skip
    print(f"in-process aligner per frame: p50 {p(local, 50)} ms, p95 {p(local, 95)} ms")


if __name__ == "__main__":
    main()
