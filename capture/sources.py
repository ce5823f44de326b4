"""Frame sources of the capture client: a BVH file paced in real time, or a TCP stream of BVH
frame lines (Perception Neuron's software broadcasts one); and how events are printed.

`header_text` (what a live session's 'start' carries) is the session protocol's
(`analysis.live.session`), re-exported here for the client's callers."""

from __future__ import annotations

import json
import socket
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.bvh import read
from analysis.live import Event, header_text

FloatArray = npt.NDArray[np.float64]
MAX_LINE_BYTES = 1 << 20


class StreamInputError(ValueError):
    """Arguments or input the stream cannot use (one line, exit 2)."""


@dataclass(frozen=True)
class Source:
    """Where frames come from: the BVH header text (no frames) and an iterator of frames."""

    header: str
    frame_time: float
    frames: Iterator[FloatArray]


def paced(frames: FloatArray, frame_time: float, speed: float | None) -> Iterator[FloatArray]:
    """The frames at ``speed`` times real time (None: no waiting)."""
    start = time.perf_counter()
    for i, frame in enumerate(frames):
        if speed is not None:
            delay = start + i * frame_time / speed - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
        yield frame


def file_source(path: str, speed: float | None) -> Source:
    motion = read(path)
    if motion.n_frames == 0:
        raise StreamInputError(f"{path} holds no frames")
    return Source(
        header_text(motion), motion.frame_time, paced(motion.frames, motion.frame_time, speed)
    )


def tcp_lines(address: str, n_channels: int) -> Iterator[FloatArray]:
    """BVH frame lines from a TCP stream (one frame per line) until the sender closes."""
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit():
        raise StreamInputError(f"--tcp takes HOST:PORT, got {address!r}")
    with socket.create_connection((host, int(port)), timeout=30) as sock:
        reader = sock.makefile("rb")
        for raw in reader:
            if len(raw) > MAX_LINE_BYTES:
                raise StreamInputError("a line of the TCP stream is longer than 1 MB")
            values = raw.split()
            if len(values) == n_channels:  # other lines (headers, keep-alives) are skipped
                yield np.array([float(v) for v in values])


def tcp_source(address: str, header_path: str | None) -> Source:
    if header_path is None:
        raise StreamInputError("--tcp needs --header FILE.bvh giving the streamed skeleton")
    motion = read(header_path)
    n = motion.skeleton.n_channels
    return Source(header_text(motion), motion.frame_time, tcp_lines(address, n))


def print_event(event: Event, out: Any = None) -> None:
    print(json.dumps(event, separators=(",", ":")), file=out or sys.stdout, flush=True)
