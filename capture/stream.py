"""``python -m capture`` (also ``python -m analysis stream``, the interface contract): a capture
client for live sessions.

    python -m analysis stream --model MODEL RECORDING.bvh[.gz] [--speed S] --json-lines
    python -m analysis stream RECORDING.bvh[.gz] --server http://HOST:PORT --token TOKEN \\
           --patient ID --exercise ID [--speed S] --json-lines
    python -m analysis stream RECORDING.bvh[.gz] --server http://HOST:PORT --token TOKEN \\
           --session ID [--speed S] --json-lines

Sends a recording's frames at S times real time (``--speed max``: as fast as the receiver takes
them) to an in-process on-line aligner (``--model``) or to a live session on the server. With
``--tcp HOST:PORT`` (and ``--header FILE.bvh`` for the skeleton) it relays a TCP stream of BVH
frame lines instead, such as the one Perception Neuron's software broadcasts. Prints one JSON
object per line: ``repetition`` and ``position`` events, then ``summary``. Exit 2 with a one-line
message for bad input or a refused token. With ``--session`` it streams into a live session a
therapist started on the patient's page instead of creating one. With ``--server``, one line on
stderr says where the session can be watched.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from analysis.bvh import AnalysisInputError, BVHError
from analysis.live import Event, LiveSession
from analysis.pipeline.model import FittedModel, ModelVersionError, load_model
from capture.remote import run_remote
from capture.sources import (
    Source,
    StreamInputError,
    file_source,
    header_text,
    print_event,
    tcp_source,
)

__all__ = [
    "Source",
    "StreamInputError",
    "add_arguments",
    "header_text",
    "run",
    "session_events",
]


def session_events(model: FittedModel, source: Source) -> Iterator[Event]:
    """Every event of an in-process `LiveSession` fed the source's frames, then the summary
    (what ``--model`` prints; the live evaluation runs the same)."""
    session = LiveSession(model, max_fps=float("inf"), burst=float("inf"))
    for event in session.handle({"type": "start", "header": source.header}):
        if event["event"] == "error":
            raise StreamInputError(event["message"])
    for seq, values in enumerate(source.frames):
        yield from session.handle({"type": "frame", "seq": seq, "values": values.tolist()})
    yield from session.end()


def run_in_process(model_path: str, source: Source) -> int:
    """Frames into an in-process `LiveSession` (no server); prints its events."""
    model = load_model(Path(model_path).read_bytes())
    for event in session_events(model, source):
        print_event(event)
    return 0


def parse_speed(text: str) -> float | None:
    if text == "max":
        return None
    try:
        speed = float(text)
    except ValueError:
        raise StreamInputError(f"--speed takes a number or 'max', got {text!r}") from None
    if not speed > 0 or not np.isfinite(speed):
        raise StreamInputError(f"--speed must be above 0, got {text!r}")
    return speed


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("recording", nargs="?", help="BVH file to send (omit with --tcp)")
    p.add_argument("--model", help="exercise model file: align in this process, no server")
    p.add_argument("--server", help="http://HOST:PORT of the dashboard")
    p.add_argument("--token", help="API token (Authorization: Token ...)")
    p.add_argument("--patient", help="patient id")
    p.add_argument("--exercise", help="exercise id")
    p.add_argument("--session", help="with --server: a live session started on the patient's page")
    p.add_argument("--speed", default="1", help="times real time, or 'max' (default 1)")
    p.add_argument("--tcp", help="relay BVH frame lines from HOST:PORT instead of a file")
    p.add_argument("--header", help="with --tcp: a BVH file giving the streamed skeleton")
    p.add_argument("--json-lines", action="store_true", help="one JSON object per line")
    p.add_argument(
        "--batch", type=int, help="with --server: frames per message (default: those of 25 ms)"
    )


def make_source(args: argparse.Namespace) -> Source:
    speed = parse_speed(args.speed)
    if args.tcp:
        return tcp_source(args.tcp, args.header or args.recording)
    if not args.recording:
        raise StreamInputError("give a RECORDING.bvh[.gz] (or --tcp HOST:PORT --header FILE)")
    return file_source(args.recording, speed)


def run(args: argparse.Namespace) -> int:
    """The ``stream`` subcommand."""
    if bool(args.model) == bool(args.server):
        raise StreamInputError("give either --model MODEL or --server URL (not both)")
    if args.server:
        needed = ("token",) if getattr(args, "session", None) else ("token", "patient", "exercise")
        missing = [f"--{n}" for n in needed if not getattr(args, n)]
        if missing:
            raise StreamInputError(f"--server needs {', '.join(missing)}")
    source = make_source(args)
    if args.model:
        return run_in_process(args.model, source)
    batch = getattr(args, "batch", None)
    if batch is not None and batch < 1:
        raise StreamInputError(f"--batch must be 1 or more, got {batch}")
    return run_remote(
        args.server, args.token, args.patient, args.exercise, source,
        batch=batch, session=getattr(args, "session", None),
    )  # fmt: skip


def parser() -> argparse.ArgumentParser:
    top = argparse.ArgumentParser(
        prog="python -m capture", description="Stream a recording to an on-line aligner."
    )
    add_arguments(top)
    return top


def main(argv: Sequence[str] | None = None) -> int:
    """The capture client's own entry point: exit 2 with one line for what it cannot use."""
    args = parser().parse_args(argv)
    try:
        return int(run(args))
    except (BVHError, AnalysisInputError, ModelVersionError, OSError, ValueError) as error:
        print(f"error: {' '.join(str(error).split()) or type(error).__name__}", file=sys.stderr)
        return 2
