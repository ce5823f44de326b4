"""Concurrent live sessions over loopback WebSockets: how many a server keeps up with.

N capture clients stream a 120 Hz recording (a UI-PRMD session resampled to 120 frames a second,
as a 120 Hz capture system sends it) at 120 frames/s each, every client with its own live session
created through ``POST /api/v1/live-sessions/``, against a real server process:

- ``runserver``: what ``make run`` serves, ``manage.py runserver`` (Daphne), in-memory channel
  layer, SQLite;
- ``redis``: the ASGI server Daphne on ``webapp.asgi:application`` with the Redis channel layer
  (``REDIS_URL=redis://127.0.0.1:6379/<db>``), SQLite; ``--processes P`` runs P Daphne
  processes, each on its own port, and the clients spread their sessions over them (a session's
  connections all go to one process: its aligner lives there), as a sticky load balancer would;
- ``uvicorn``: the same with the ASGI server Uvicorn (uvloop, the websockets library, no
  per-message compression: frames of numbers on a clinic's network need the processor more
  than the bandwidth), ``--processes P`` likewise.

``--batch K`` sends K frames per message (``{"type": "frames", ...}``, as ``python -m analysis
stream --server`` does: 3 at 120 frames/s); the latency of every frame of a batch is counted
from the time its first frame was due, so the wait for the batch's other frames is in it.
``--frames json,binary`` measures both forms of a frame message in one run, JSON text and
binary float32 (`analysis.live.frames`, what ``stream --server`` sends to a server that reads
it), each configuration with each form, so the server's processor time per frame and the
largest N of the two can be set side by side.

Per frame that gets an answer (the aligner thins a 120 Hz stream to the exercise model's 30
frames a second, so every fourth frame is aligned and answered with a position event), the
client measures frame sent -> position event received: the frame-to-guidance latency. No frame
lost: no error event (a dropped, out-of-order or refused frame is answered with one), every
aligned frame answered, and the server holding every frame sent (its ``ready`` event's
``next_seq`` on a second connection after the stream). N grows (10, 20, 35, 50, 70, 100) until
p95 passes 50 ms or a frame is lost; the table gives each step and the largest N that passed.
The clients run in one process on the same machine as the server.

    .venv/bin/python -m bench.bench_live [--servers runserver,redis,uvicorn] [--counts 10,20,35]
        [--seconds 10] [--batch 3] [--processes 2] [--frames json,binary] [--redis-db 14]
        [--markdown FILE]

``--server-cpus 1`` pins the server processes to those cores and the clients' process (this
one) to the others, so that the clients' work is not counted against the server's cores: on a
2-core machine the server then has one core to itself.

``--aligner`` also prints the in-process aligner's time per frame (``stream --model``);
``--stages`` prints only its processor time per frame sent by step (features, counter,
open-end row, FP-C step, repetition end); ``--split`` only the consumer's in-process work per
frame for the bench's session at ``--fps`` (session set-up, reading the binary messages, the
aligner's per-frame steps, the repetition's end), the rest of the server's time per frame being
the WebSocket and Channels path and the session's creation and connections.
``--server-profile FILE`` runs Uvicorn under cProfile from the warm-up on
(`bench.profiled_server`).
"""

from __future__ import annotations

import argparse
import asyncio
import datetime as dt
import json
import os
import platform
import random
import signal
import subprocess
import sys
import tempfile
import time
import urllib.request
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from analysis.live.frames import decode_frames, encode_frames
from bench.nginx_proxy import free_port, start_proxy

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "data" / "ui-prmd"
TUTOR = "sessions/m07_s01_correct.bvh.gz"
SESSION = "sessions/m07_s03_incorrect.bvh.gz"
TARGET_MS = 50.0
START_SECONDS = 180  # a server's start-up on a busy machine: imports and the first page


def machine() -> str:
    """The processor model, core count and memory, e.g. "2-core AMD EPYC, 24 GiB"."""
    from bench.eval_live import machine as described

    return described()


@dataclass
class Step:
    server: str
    sessions: int
    p50: float = float("nan")
    p95: float = float("nan")
    sent_p95: float = float("nan")  # from the message's send time (without the batch's wait)
    answered: int = 0
    expected: int = 0
    errors: int = 0
    held: int = 0  # sessions whose server state holds every frame sent
    server_p95: float = float("nan")  # frame received -> position event sent, in the server
    server_cpu: float = float("nan")  # processor seconds the server used during the step
    client_cpu: float = float("nan")  # processor seconds the clients' process used
    sent: int = 0
    seconds: float = 0.0
    fps: float = 120.0  # each client's frames per second
    notes: list[str] = field(default_factory=list)

    @property
    def lost(self) -> bool:
        return self.errors > 0 or self.answered < self.expected or self.held < self.sessions

    @property
    def passed(self) -> bool:
        return not self.lost and self.p95 <= TARGET_MS


# --- the world the server serves --------------------------------------------------------------

SETUP = """
import json, django
django.setup()
from django.core.management import call_command
call_command("migrate", verbosity=0, interactive=False)
from tests.personas import make_exercise, make_world
from webapp.accounts.tokens import issue_token
from workers.exercise_models import load_or_build
w = make_world()
exercise = make_exercise(w.clinic, "Shoulder abduction", "%s")
load_or_build(exercise)  # fitted and stored now, so the server only loads it
_, key = issue_token(w.therapist, "bench")
print(json.dumps({"token": key, "patient": str(w.patient.pk), "exercise": str(exercise.pk)}))
"""


def server_env(folder: Path, redis_url: str | None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("REDIS_URL", "DATABASE_URL")}
    env.update(DATA_DIR=str(folder), DJANGO_SETTINGS_MODULE="webapp.settings", PYTHONPATH=str(ROOT))
    if redis_url:
        env["REDIS_URL"] = redis_url
    return env


def setup_world(env: dict[str, str]) -> dict[str, str]:
    out = subprocess.run(
        [sys.executable, "-c", SETUP % TUTOR], env=env, cwd=ROOT, check=True,
        capture_output=True, text=True,
    )  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])


def start_server(
    kind: str,
    env: dict[str, str],
    port: int,
    log: Path,
    cpus: set[int] | None = None,
    *,
    profile: Path | None = None,
) -> subprocess.Popen:
    """A server process answering on ``port``; ``profile``: run Uvicorn under cProfile
    (`bench.profiled_server`), writing its statistics there when it stops."""
    if kind == "runserver":
        argv = [sys.executable, "manage.py", "runserver", f"127.0.0.1:{port}", "--noreload"]
    elif kind == "uvicorn":
        argv = [sys.executable, "-m", "uvicorn", "webapp.asgi:application", "--host", "127.0.0.1",
                "--port", str(port), "--log-level", "warning", "--no-access-log",
                "--ws-per-message-deflate", "false", "--ws-max-size", str(1 << 20),
                # after a run its Channels tasks keep it waiting past the 20 s stop_server allows
                "--timeout-graceful-shutdown", "3"]  # fmt: skip
        if profile is not None:
            argv[1:3] = ["-m", "bench.profiled_server", str(profile)]
    elif kind == "gunicorn":  # pages and the API as docker-compose's `web` serves them (WSGI)
        argv = [sys.executable, "-m", "gunicorn", "webapp.wsgi:application", "--bind",
                f"127.0.0.1:{port}", "--workers", "2"]  # fmt: skip
    else:
        argv = [sys.executable, "-m", "daphne", "-b", "127.0.0.1", "-p", str(port),
                "-v", "0", "webapp.asgi:application"]  # fmt: skip
    handle = log.open("w")
    if cpus:  # taskset execs the server: the same process id, pinned from its first instruction
        argv = ["taskset", "-c", ",".join(map(str, sorted(cpus))), *argv]
    proc = subprocess.Popen(argv, env=env, cwd=ROOT, stdout=handle, stderr=subprocess.STDOUT)
    deadline = time.monotonic() + START_SECONDS
    while time.monotonic() < deadline:
        try:
            urllib.request.urlopen(f"http://127.0.0.1:{port}/healthz", timeout=2)
            return proc
        except OSError:
            if proc.poll() is not None:
                raise RuntimeError(f"the {kind} server stopped: see {log}") from None
            time.sleep(0.5)
    proc.terminate()
    raise RuntimeError(f"the {kind} server did not answer in {START_SECONDS} s: see {log}")


def cpu_seconds(pid: int) -> float:
    """Processor time (user + system) the process has used so far, from /proc."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def stop_server(proc: subprocess.Popen) -> None:
    proc.terminate()
    try:
        proc.wait(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def create_session(base: str, world: dict[str, str]) -> str:
    body = json.dumps({"patient": world["patient"], "exercise": world["exercise"]}).encode()
    request = urllib.request.Request(
        f"{base}/api/v1/live-sessions/", data=body, method="POST",
        headers={"Authorization": f"Token {world['token']}", "Content-Type": "application/json"},
    )  # fmt: skip
    with urllib.request.urlopen(request, timeout=30) as response:
        return str(json.load(response)["ws"])


# --- the clients ------------------------------------------------------------------------------


@dataclass
class Recording120:
    header: str
    frames: list[list[float]]  # each frame's values
    batch: int = 1
    binary: bool = False  # float32 binary messages instead of JSON text
    messages: list[tuple[int, str | bytes]] = field(default_factory=list)  # (first seq, message)

    def __post_init__(self) -> None:
        for first in range(0, len(self.frames), self.batch):
            part = self.frames[first : first + self.batch]
            self.messages.append((first, self.message(first, part)))

    def message(self, first: int, part: list[list[float]]) -> str | bytes:
        if self.binary:
            return encode_frames(first, np.array(part))
        body = (
            {"type": "frame", "seq": first, "values": part[0]}
            if self.batch == 1
            else {"type": "frames", "seq": first, "frames": part}
        )
        return json.dumps(body)

    @property
    def form(self) -> str:
        return "binary" if self.binary else "JSON"


def recording_120(seconds: float, fps: float, batch: int, binary: bool = False) -> Recording120:
    from analysis.bvh import read
    from analysis.kinematics import resample
    from analysis.live import header_text

    motion = resample(read(DATA / SESSION), fps)
    n = min(motion.n_frames, int(seconds * fps))
    frames = [[round(v, 4) for v in row] for row in motion.frames[:n].tolist()]
    return Recording120(header_text(motion), frames, batch, binary)


@dataclass
class ClientResult:
    latencies: list[float] = field(default_factory=list)  # from the batch's first frame due
    sent_latencies: list[float] = field(default_factory=list)  # from the message sent
    server_ms: list[float] = field(default_factory=list)  # receive -> send, in the server
    errors: int = 0
    held: bool = False


async def client(url: str, token: str, rec: Recording120, fps: float, begin: float) -> ClientResult:
    from websockets.asyncio.client import connect

    result = ClientResult()
    sent: dict[int, float] = {}  # frame -> when its batch's first frame was due
    sent_at: dict[int, float] = {}  # frame -> when its message was sent
    headers = {"Authorization": f"Token {token}"}
    async with connect(url, additional_headers=headers, max_size=None) as ws:
        await ws.send(json.dumps({"type": "start", "header": rec.header}))
        while json.loads(await ws.recv())["event"] != "ready":
            pass

        async def receive() -> None:
            async for raw in ws:
                decoded = json.loads(raw)
                for event in decoded if isinstance(decoded, list) else [decoded]:
                    if event["event"] == "position":
                        now = time.perf_counter()
                        result.latencies.append((now - sent[event["frame"]]) * 1e3)
                        result.sent_latencies.append((now - sent_at[event["frame"]]) * 1e3)
                        result.server_ms.append(event["latency_ms"])
                    elif event["event"] == "error":
                        result.errors += 1

        reader = asyncio.create_task(receive())
        # clients are not in step with each other: each sends its messages at its own phase of
        # the message period (a batch's frame times), as independent capture systems would
        phase = random.random() * rec.batch / fps
        for first, message in rec.messages:
            last = min(first + rec.batch, len(rec.frames)) - 1
            delay = begin + phase + last / fps - time.perf_counter()
            if delay > 0:
                await asyncio.sleep(delay)
            # the first frame was due (last - first) frames ago: its wait counts
            now = time.perf_counter()
            due = min(now, begin + phase + first / fps)
            for seq in range(first, last + 1):
                sent[seq], sent_at[seq] = due, now
            await ws.send(message)
        await asyncio.sleep(1.0)  # the last answers
        reader.cancel()
    async with connect(url, additional_headers=headers) as ws:  # what the server holds
        ready = json.loads(await asyncio.wait_for(ws.recv(), 30))
        result.held = ready.get("next_seq") == len(rec.frames)
    return result


async def run_clients(
    bases: list[str],
    world: dict[str, str],
    n: int,
    rec: Recording120,
    fps: float,
    *,
    warmed: Callable[[], None],
    processes: list[str] | None = None,
) -> list[ClientResult]:
    """N sessions spread over ``bases``, after one unmeasured short session on each of the
    ``processes`` (``bases`` unless given: a proxy's processes are warmed directly)."""
    token = world["token"]
    # one short session per process first, unmeasured: it loads the model and compiled kernels
    warm = Recording120(rec.header, rec.frames[: int(fps)], rec.batch, rec.binary)
    for base in processes or bases:
        url = base.replace("http://", "ws://") + create_session(base, world)
        await client(url, token, warm, fps, time.perf_counter())
    warmed()
    urls = []
    for i in range(n):  # sessions spread over the processes, each session's connections in one
        base = bases[i % len(bases)]
        urls.append(base.replace("http://", "ws://") + create_session(base, world))
    begin = time.perf_counter() + 1.0
    return await asyncio.gather(*(client(url, token, rec, fps, begin) for url in urls))


@dataclass
class Context:
    env: dict[str, str]
    world: dict[str, str]
    rec: Recording120
    fps: float
    folder: Path
    processes: int = 1
    proxy: bool = False  # through docker-compose's nginx proxy (deploy/), 2 processes
    server_cpus: set[int] | None = None  # the cores the server processes are pinned to
    profile: Path | None = None  # profile Uvicorn after the warm-up: statistics to this stem


def label(kind: str, ctx: Context) -> str:
    name = {"runserver": "runserver", "uvicorn": "Uvicorn + Redis"}.get(kind, "Daphne + Redis")
    if ctx.processes > 1 and kind != "runserver":
        name += f", {ctx.processes} processes"
    if ctx.proxy:
        name += " behind nginx"
    if ctx.server_cpus:
        name += f", server on core {','.join(map(str, sorted(ctx.server_cpus)))} alone"
    plural = "s" if ctx.rec.batch > 1 else ""
    return f"{name}, {ctx.rec.batch} frame{plural}/message, {ctx.rec.form}"


def measure(kind: str, n: int, ctx: Context) -> Step:
    env, rec, fps = ctx.env, ctx.rec, ctx.fps
    logs = ctx.folder.parent / "bench-live-logs"  # kept after the run
    logs.mkdir(exist_ok=True)
    count = 1 if kind == "runserver" else ctx.processes
    ports = [free_port() for _ in range(count)]
    stem = ctx.profile
    procs = [
        start_server(kind, env, p, logs / f"{kind}-{n}-{i}.log", ctx.server_cpus,
                     profile=None if stem is None else stem.with_name(f"{stem.name}-{n}-{i}.prof"))
        for i, p in enumerate(ports)
    ]  # fmt: skip
    step = Step(label(kind, ctx), n, sent=n * len(rec.frames), fps=fps)
    started, cpu = time.perf_counter(), [0.0]
    bases = [f"http://127.0.0.1:{port}" for port in ports]

    def warmed() -> None:  # processor time from here: imports and model loading are not in it
        cpu[0] = sum(cpu_seconds(p.pid) for p in procs)
        if ctx.profile is not None:  # `bench.profiled_server` starts its profile
            for proc in procs:
                proc.send_signal(signal.SIGUSR1)

    client_cpu = time.process_time()
    try:
        results = asyncio.run(clients_of(bases, ctx, n, warmed, logs / f"nginx-{kind}-{n}"))
        step.client_cpu = time.process_time() - client_cpu
        step.server_cpu = sum(cpu_seconds(p.pid) for p in procs) - cpu[0]
    except Exception as error:  # a refused connection or a timeout is a failed step
        step.notes.append(f"{type(error).__name__}: {error}")
        step.errors = 1
        return step
    finally:
        for proc in procs:
            stop_server(proc)
    step.seconds = time.perf_counter() - started
    lat = [v for r in results for v in r.latencies]
    inside = [v for r in results for v in r.server_ms]
    step.server_p95 = float(np.percentile(inside, 95)) if inside else float("nan")
    step.p50, step.p95 = (float(np.percentile(lat, q)) for q in (50, 95)) if lat else (0.0, 0.0)
    on_send = [v for r in results for v in r.sent_latencies]
    step.sent_p95 = float(np.percentile(on_send, 95)) if on_send else float("nan")
    step.answered = len(lat)
    step.expected = n * len(range(0, len(rec.frames), round(fps / 30)))
    step.errors = sum(r.errors for r in results)
    step.held = sum(r.held for r in results)
    return step


async def clients_of(
    bases: list[str], ctx: Context, n: int, warmed: Callable[[], None], logs: Path
) -> list[ClientResult]:
    """The clients against the processes, or through the proxy in front of two of them (its
    `web` is the first process: any of them serves the API that creates the sessions)."""
    if not ctx.proxy:
        return await run_clients(bases, ctx.world, n, ctx.rec, ctx.fps, warmed=warmed)
    hosts = [base.removeprefix("http://") for base in bases]
    proxy = start_proxy(logs, hosts[0], (hosts[0], hosts[1]))
    try:
        return await run_clients(
            [proxy.url], ctx.world, n, ctx.rec, ctx.fps, warmed=warmed, processes=bases
        )
    finally:
        proxy.stop()


# --- report -----------------------------------------------------------------------------------


def row(s: Step) -> str:
    verdict = "yes" if s.passed else "no"
    lost = "none" if not s.lost else (
        f"{s.errors} errors, {s.expected - s.answered} unanswered, "
        f"{s.sessions - s.held} sessions short"
    )  # fmt: skip
    cpu = 1e3 * s.server_cpu / max(s.sent, 1)
    figures = f"{s.p50:.1f} | {s.p95:.1f} | {s.sent_p95:.1f} | {s.server_p95:.1f} | {cpu:.2f}"
    return (
        f"| {s.server} | {s.sessions} | {s.sessions * s.fps:g} | {figures} | {lost} | {verdict} |"
    )


def report(steps: list[Step], args: argparse.Namespace, load: str) -> str:
    lines = [
        "## Concurrent live sessions",
        "",
        f"Measured {dt.date.today().isoformat()} on the project's VM ({machine()}, Python "
        f"{platform.python_version()}); load average {load} before the run. Clients "
        "and server on the same machine, over loopback; clients start at random phases of "
        "the message period, as independent capture systems would.",
        f"Command: `.venv/bin/python -m bench.bench_live --servers {args.servers} --counts "
        f"{args.counts} --seconds {args.seconds:g} --batch {args.batch} --processes "
        f"{args.processes} --frames {args.frames} --fps {args.fps:g}"
        f"{' --proxy' if args.proxy else ''}"
        f"{f' --server-cpus {args.server_cpus}' if args.server_cpus else ''}`.",
        "",
        f"Each client streams {args.seconds:g} s of a {args.fps:g} Hz recording (UI-PRMD "
        f"`{SESSION}` resampled) at {args.fps:g} frames/s to its own live session, one frame or "
        "a batch of frames per message; latency is frame due → position event received for "
        "the frames the aligner answers (those at the exercise model's 30 frames/s: every "
        "fourth at 120 frames/s), counted from when the first frame of the frame's message was "
        "due, so a batch's wait for its last frame is in it (two frame times for 3 frames). "
        "From the message sent: the same without that wait. In the consumer: message received "
        "→ position event sent, measured by the server (queueing before the consumer is not "
        "in it). Server processor time: user + system time of the server processes per frame "
        "sent, from after a one-second warm-up session per process (imports and model "
        "loading are not in it; session set-up is).",
        "",
        "| server | sessions | frames/s in | p50 latency (ms) | p95 latency (ms) | p95 from the "
        "message sent (ms) | p95 in the consumer (ms) | server processor time per frame (ms) | "
        "frames lost | p95 ≤ 50 ms, none lost |",
        "|---|---|---|---|---|---|---|---|---|---|",
        *(row(s) for s in steps),
        "",
    ]
    for name in dict.fromkeys(s.server for s in steps):
        ok = [s.sessions for s in steps if s.server == name and s.passed]
        lines.append(f"- {name}: largest N that passed: {max(ok) if ok else 'none'}.")
    notes = [f"- {s.server} N={s.sessions}: {n}" for s in steps for n in s.notes]
    return "\n".join(lines + compared(steps) + notes)


def compared(steps: list[Step]) -> list[str]:
    """Server processor time per frame, binary against JSON, over the sizes N both measured
    in the same configuration (the same label but for the form)."""
    lines = []
    for name in dict.fromkeys(s.server for s in steps if s.server.endswith(", binary")):
        base = name.removesuffix(", binary")
        binary, text = per_frame_ms(steps, name), per_frame_ms(steps, f"{base}, JSON")
        both = sorted(set(binary) & set(text))
        if not both:
            continue
        binary_ms = float(np.mean([binary[n] for n in both]))
        text_ms = float(np.mean([text[n] for n in both]))
        lines.append(
            f"- {base}: server processor time per frame {binary_ms:.3f} ms binary against "
            f"{text_ms:.3f} ms JSON ({binary_ms / text_ms:.2f}×, mean over N = "
            f"{', '.join(map(str, both))})."
        )
    return lines


def per_frame_ms(steps: list[Step], name: str) -> dict[int, float]:
    """Server processor milliseconds per frame sent, by N (a second try replaces the first)."""
    return {
        s.sessions: 1e3 * s.server_cpu / s.sent
        for s in steps
        if s.server == name and s.sent and not np.isnan(s.server_cpu)
    }


def aligner_times() -> None:
    from analysis.bvh import read
    from analysis.live import LiveAligner
    from bench.eval_live import tutor_model

    model = tutor_model(DATA, "m07")
    motion = read(DATA / SESSION)
    for _ in range(2):  # the first pass loads the compiled kernels
        aligner = LiveAligner(model, motion.skeleton, motion.fps)
        for values in motion.frames:
            aligner.push(values)
    p50, p95 = np.percentile(aligner.latencies_ms, [50, 95])
    print(f"in-process aligner per frame: p50 {p50:.3f} ms, p95 {p95:.3f} ms")


def reading_times(fps: float, batch: int) -> None:
    """Processor time per frame sent at ``fps`` in messages of ``batch`` frames: reading it in
    each form up to the aligner (JSON: orjson, then the session's check of its values; binary:
    `analysis.live.frames.decode_frames` and the finiteness check), against aligning it (the
    aligner thins the stream to the model's 30 frames/s). The best of 5 passes, the machine
    being shared."""
    import orjson

    from analysis.bvh import read
    from analysis.live import LiveAligner
    from analysis.live.session import parse_values
    from bench.eval_live import tutor_model

    texts, binary = (recording_120(30.0, fps, batch, form).messages for form in (False, True))
    frames = sum(len(orjson.loads(text)["frames"]) for _, text in texts)

    def read_json() -> None:
        for _, text in texts:
            for seq, values in enumerate(orjson.loads(text)["frames"]):
                parse_values(values, len(values), seq)

    def read_binary() -> None:
        for _, data in binary:
            assert isinstance(data, bytes)  # the binary form's messages
            np.isfinite(decode_frames(data).values).all(axis=1)

    model, rec = tutor_model(DATA, "m07"), recording_120(30.0, fps, 1)
    skeleton = read(rec.header.encode(), max_values=0).skeleton

    def align() -> None:
        aligner = LiveAligner(model, skeleton, fps)
        for values in rec.frames:
            aligner.push(np.asarray(values))

    for name, run in (("reading, JSON", read_json), ("reading, binary", read_binary),
                      ("aligning", align)):  # fmt: skip
        best = min(process_seconds(run) for _ in range(5))
        print(f"{name}: {1e6 * best / frames:.1f} µs of processor time per frame sent")


def stage_times(passes: int = 3) -> None:
    """Processor time (``time.thread_time``) per frame sent of the in-process aligner on the
    bench's 120 Hz stream, by step: each step's method wrapped in a timer, the median of
    ``passes`` passes after a warm-up (the machine being shared, processor time, not wall)."""
    from analysis.bvh import read
    from analysis.kinematics import resample
    from analysis.live import LiveAligner
    from analysis.online import aligners, counting
    from bench.eval_live import tutor_model

    spent: dict[str, float] = {}
    steps = {"features": (LiveAligner, "_features"),
             "counter": (counting.RepetitionCounter, "push"),
             "open-end row": (aligners.OpenEndAligner, "push_finite"),
             "FP-C step": (aligners.ForwardPlotAligner, "push"),
             "repetition end": (LiveAligner, "_repetition")}  # fmt: skip
    for name, (owner, method) in steps.items():
        setattr(owner, method, _timed(getattr(owner, method), name, spent))
    model = tutor_model(DATA, "m07")
    motion = resample(read(DATA / SESSION), 120.0)
    frames = [np.ascontiguousarray(v) for v in motion.frames]
    runs: list[dict[str, float]] = []
    for _ in range(passes + 1):  # the first pass loads the compiled kernels
        spent.clear()
        started = time.thread_time()
        aligner = LiveAligner(model, motion.skeleton, motion.fps)
        for values in frames:
            aligner.push(values)
        aligner.finish()
        runs.append({"all": time.thread_time() - started, **spent})
    for name in runs[-1]:
        micro = 1e6 * float(np.median([r.get(name, 0.0) for r in runs[1:]])) / len(frames)
        print(f"{name}: {micro:.1f} µs of processor time per frame sent")


def split_times(fps: float, seconds: float, batch: int, sessions: int = 20) -> None:
    """Processor time (``time.thread_time``) per frame sent of what the server's consumer does
    in-process for a session of the bench (`recording_120` in binary messages of ``batch``
    frames, each read by `decode_frames` and answered by `take_frames`): the session's set-up
    (its ``start``), reading the messages, the aligner's per-frame steps and the repetition's
    end; the median over ``sessions`` sessions after a warm-up one. What the server spends
    beyond these (WebSocket, Channels, sending, the session's creation and connections) is its
    processor time per frame less their sum."""
    from analysis.live import LiveAligner, LiveSession
    from analysis.live.frames import take_frames
    from bench.eval_live import tutor_model

    rec = recording_120(seconds, fps, batch, binary=True)
    model = tutor_model(DATA, "m07")
    spent: dict[str, float] = {}
    LiveAligner._repetition = _timed(LiveAligner._repetition, "end", spent)  # type: ignore[method-assign]
    runs: list[dict[str, float]] = []
    for _ in range(sessions + 1):  # the first loads the compiled kernels
        spent.clear()
        session = LiveSession(model, max_fps=1e9, burst=1e9)  # no rate limit in a loop
        started = time.thread_time()
        session.handle({"type": "start", "header": rec.header})
        spent["set-up"] = time.thread_time() - started
        reading = aligning = 0.0
        for _, message in rec.messages:
            before = time.thread_time()
            block = decode_frames(message)  # type: ignore[arg-type]
            read = time.thread_time()
            take_frames(session, block)
            reading, aligning = reading + read - before, aligning + time.thread_time() - read
        assert session.aligner is not None
        runs.append({**spent, "reading": reading, "frames": aligning - spent.get("end", 0.0),
                     "repetitions": len(session.aligner.repetitions)})  # fmt: skip
    frames = len(rec.frames)
    median = {k: float(np.median([r.get(k, 0.0) for r in runs[1:]])) for k in runs[-1]}
    print(f"{fps:g} frames/s, {seconds:g} s ({frames} frames, {batch} a message, "
          f"{median['repetitions']:g} repetitions), median of {sessions} sessions:")  # fmt: skip
    total = 0.0
    for name, label in (("set-up", "session set-up"), ("reading", "reading the messages"),
                        ("frames", "per-frame steps"), ("end", "repetition's end")):  # fmt: skip
        total += median.get(name, 0.0)
        print(f"  {label}: {1e6 * median.get(name, 0.0) / frames:.1f} µs per frame sent")
    print(
        f"  together: {1e6 * total / frames:.1f} µs per frame sent; set-up "
        f"{1e3 * median['set-up']:.2f} ms a session, the end "
        f"{1e3 * median.get('end', 0.0) / max(median['repetitions'], 1):.2f} ms a repetition"
    )


def _timed(method: Callable, name: str, spent: dict[str, float]) -> Callable:
    def timed(*args: object) -> object:
        started = time.thread_time()
        try:
            return method(*args)
        finally:
            spent[name] = spent.get(name, 0.0) + time.thread_time() - started

    return timed


def process_seconds(run: Callable[[], None]) -> float:
    started = time.process_time()
    run()
    return time.process_time() - started


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--servers", default="runserver,redis,uvicorn")
    parser.add_argument("--counts", default="10,20,35,50,70,100")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--fps", type=float, default=120.0)
    parser.add_argument("--redis-db", type=int, default=14)
    parser.add_argument("--batch", default="1,3", help="frames per message, e.g. 1,3")
    parser.add_argument("--processes", default="1,2", help="server processes (redis, uvicorn)")
    parser.add_argument("--frames", default="json,binary", help="frame messages: json, binary")
    parser.add_argument("--markdown", type=Path)
    parser.add_argument("--aligner", action="store_true")
    parser.add_argument(
        "--stages", action="store_true",
        help="the in-process aligner's processor time per frame sent, by step, then stop",
    )  # fmt: skip
    parser.add_argument(
        "--split", action="store_true",
        help="only print the consumer's in-process work per frame (--fps, --seconds, --batch)",
    )  # fmt: skip
    parser.add_argument(
        "--reading", action="store_true",
        help="only print the processor time to read a frame (JSON, binary) and to align it",
    )  # fmt: skip
    parser.add_argument(
        "--proxy", action="store_true",
        help="also through docker-compose's nginx proxy in front of 2 processes (redis, uvicorn)",
    )  # fmt: skip
    parser.add_argument(
        "--server-profile", type=Path,
        help="run Uvicorn under cProfile after the warm-up; statistics to FILE-N-i.prof",
    )  # fmt: skip
    parser.add_argument(
        "--server-cpus", default="",
        help="cores for the server processes, e.g. 1; the clients then run on the other cores",
    )  # fmt: skip
    args = parser.parse_args(argv)
    server_cpus = pin_clients_away(args.server_cpus)
    if args.aligner:
        aligner_times()
    if args.stages:
        stage_times()
        return
    if args.split:
        split_times(args.fps, args.seconds, int(str(args.batch).split(",")[-1]))
        return
    if args.reading:
        reading_times(args.fps, int(str(args.batch).split(",")[-1]))
        return
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    steps: list[Step] = []
    for kind in args.servers.split(","):
        redis_url = None if kind == "runserver" else f"redis://127.0.0.1:6379/{args.redis_db}"
        with tempfile.TemporaryDirectory(prefix=f"bench-live-{kind}-") as tmp:
            folder = Path(tmp)
            env = server_env(folder, redis_url)
            world = setup_world(env)
            for batch, processes, proxy in configurations(kind, args):
                ctxs = [
                    Context(env, world, recording_120(args.seconds, args.fps, batch, binary),
                            args.fps, folder, processes, proxy, server_cpus,
                            args.server_profile)
                    for binary in (form == "binary" for form in args.frames.split(","))
                ]  # fmt: skip
                steps += grow(kind, ctxs, [int(v) for v in args.counts.split(",")])
    text = report(steps, args, load)
    print(text)
    if args.markdown:
        args.markdown.write_text(text + "\n", encoding="utf-8")


def pin_clients_away(server_cpus: str) -> set[int] | None:
    """The server's cores from ``--server-cpus`` ("1", "0,1"; empty: none), with this process,
    which runs the clients, pinned to the machine's other cores."""
    if not server_cpus:
        return None
    cores = {int(v) for v in server_cpus.split(",")}
    others = os.sched_getaffinity(0) - cores
    if not others:
        raise SystemExit("--server-cpus leaves no core for the clients")
    os.sched_setaffinity(0, others)
    return cores


def configurations(kind: str, args: argparse.Namespace) -> list[tuple[int, int, bool]]:
    """(frames per message, server processes, through the proxy) to measure for the kind."""
    batches = [int(v) for v in str(args.batch).split(",")]
    processes = [1] if kind == "runserver" else [int(v) for v in str(args.processes).split(",")]
    plain = [(b, p, False) for b in batches for p in processes]
    return plain + ([(b, 2, True) for b in batches] if args.proxy and kind != "runserver" else [])


def grow(kind: str, ctxs: list[Context], counts: list[int]) -> list[Step]:
    """Steps of growing N until one fails (twice: the machine is shared), for each form of
    frame message; the forms take turns at each N, so a change in the machine's load between
    steps falls on both."""
    steps: list[Step] = []
    growing = list(ctxs)
    for n in counts:
        for ctx in list(growing):
            step = measure_twice(kind, n, ctx, steps)
            if not step.passed:
                growing.remove(ctx)
    return steps


def measure_twice(kind: str, n: int, ctx: Context, steps: list[Step]) -> Step:
    """One step at N, tried again when it fails; appended to ``steps`` and printed."""
    step = measure(kind, n, ctx)
    if not step.passed:  # the machine is shared: a failed step is tried once more
        steps.append(step)
        print(row(step), "(first try)", flush=True)
        step = measure(kind, n, ctx)
        step.notes.append("second try (the first is the row above)")
    steps.append(step)
    per_frame = 1e3 * step.server_cpu / max(step.sent, 1)
    print(
        row(step),
        f"server p95 {step.server_p95:.1f} ms, server CPU "
        f"{step.server_cpu:.1f} s = {per_frame:.3f} ms/frame, clients' CPU "
        f"{step.client_cpu:.1f} s in {step.seconds:.1f} s",
        *step.notes,
        flush=True,
    )
    return step


if __name__ == "__main__":
    main()
