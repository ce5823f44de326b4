"""The live-session protocol, without any server: messages in, events out.

A capture client sends JSON messages over a WebSocket (the server) or calls `handle` directly:

    {"type": "start", "header": "HIERARCHY ... MOTION\\nFrames: 0\\nFrame Time: 0.0333\\n"}
    {"type": "frame", "seq": 0, "values": [c1, c2, ...]}       # or "line": "c1 c2 ..." (BVH text)
    {"type": "frames", "seq": 3, "frames": [[c1, ...], "c1 c2 ...", ...]}  # a batch: seq 3, 4, ...
    {"type": "end"}

Events back: ``ready`` (with ``next_seq``: where a reconnecting client resumes, and ``max_fps``),
``position`` and ``repetition`` (see `analysis.live.aligner`), ``error`` (``code``, ``message``,
``seq``), and last ``summary``. A bad message gets an error event and changes nothing: a frame
with the wrong number of values, a value that is not a finite number, a sequence number other
than the next one (a repeat of an earlier one is ignored with a ``duplicate`` error, so a client
resending after a reconnect loses nothing), or a frame over the rate limit (dropped and counted).

A batch (up to `MAX_BATCH` frames, numbered from its ``seq``) saves a message per frame: a
capture client at 120 frames/s sends three at a time, which costs the server a third of the
messages for at most 17 ms more wait on the first frame. Its frames go through the same checks
one by one; a refused frame of a batch gets its error and uses up its sequence number, so the
frames after it in the batch are still taken (a batch cannot be half resent). A batch that
starts after the next expected frame is refused whole (``out-of-order``); the frames of one that
starts before it were already received and are skipped with one ``duplicate`` error.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.bvh import AnalysisInputError, BVHError, Motion, dumps, read
from analysis.live.aligner import LiveAligner, LiveOptions
from analysis.live.words import Event
from analysis.pipeline.model import FittedModel

FloatArray = npt.NDArray[np.float64]
MAX_HEADER_BYTES = 1 << 20
MAX_BATCH = 64  # frames in one batch message
MAX_VALUES = 8_000_000  # values kept per session, as for an upload (a 30-minute session)


def header_text(motion: Motion) -> str:
    """The BVH text of the skeleton with no frames (what a live session's 'start' carries)."""
    return dumps(motion.with_frames(np.zeros((0, motion.skeleton.n_channels))))


class ProtocolError(ValueError):
    """A message the session cannot use; ``code`` names the kind."""

    def __init__(self, code: str, message: str, seq: int | None = None) -> None:
        super().__init__(message)
        self.code, self.seq = code, seq


@dataclass
class RateLimit:
    """Token bucket: ``rate`` frames per second on average, bursts of ``burst`` frames."""

    rate: float
    burst: float
    clock: Callable[[], float] = time.monotonic
    _tokens: float = field(init=False, default=0.0)
    _last: float | None = field(init=False, default=None)

    def allow(self) -> bool:
        now = self.clock()
        if self._last is None:
            self._tokens = self.burst
        else:
            self._tokens = min(self.burst, self._tokens + (now - self._last) * self.rate)
        self._last = now
        if self._tokens < 1.0:
            return False
        self._tokens -= 1.0
        return True


def _seq(message: dict[str, Any]) -> int:
    seq = message.get("seq")
    if not isinstance(seq, int) or isinstance(seq, bool):
        raise ProtocolError("bad-seq", "a frame needs an integer 'seq'")
    return seq


def error_event(error: ProtocolError) -> Event:
    return {"event": "error", "code": error.code, "message": str(error), "seq": error.seq}


def parse_values(raw: Any, n_channels: int, seq: int) -> FloatArray:
    """A frame's channel values (C,) from a list of numbers, a BVH frame line or a row of a
    binary message (`analysis.live.frames`, already numbers), or ProtocolError saying what is
    wrong with them."""
    if isinstance(raw, np.ndarray):
        values = raw
        if values.shape != (n_channels,):
            text = f"frame {seq} has {values.size} values; the skeleton has {n_channels}"
            raise ProtocolError("value-count", text, seq)
    else:
        values = _listed_values(raw, n_channels, seq)
    if not np.isfinite(values).all():
        raise ProtocolError("not-finite", f"frame {seq} holds NaN or infinite values", seq)
    return values


def _listed_values(raw: Any, n_channels: int, seq: int) -> FloatArray:
    if isinstance(raw, str):
        raw = raw.split()
    if not isinstance(raw, list):
        raise ProtocolError("bad-frame", "a frame needs 'values' (a list) or 'line' (text)", seq)
    if len(raw) != n_channels:
        raise ProtocolError(
            "value-count", f"frame {seq} has {len(raw)} values; the skeleton has {n_channels}", seq
        )
    try:  # numpy reads a list of numbers (or of number strings) in one call
        values = np.array(raw, dtype=np.float64)
        if values.ndim != 1:
            raise ValueError("nested")
    except (TypeError, ValueError):
        text = f"frame {seq} holds a value that is not a number"
        raise ProtocolError("not-a-number", text, seq) from None
    return values


class LiveSession:
    """One session's state: the skeleton, the frames kept (for the recording), the aligner."""

    def __init__(
        self,
        model: FittedModel,
        *,
        max_fps: float = 1000.0,
        burst: float = 250.0,
        options: LiveOptions | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.model, self.options = model, options
        self.max_fps = max_fps
        self.limit = RateLimit(max_fps, burst, clock)
        self.motion: Motion | None = None
        self.aligner: LiveAligner | None = None
        self.frames: list[FloatArray] = []
        self.skipped = 0  # sequence numbers used up by refused frames of batches
        self.dropped = 0
        self.errors = 0
        self.ended = False
        self.delivery_ms: list[float] = []  # frame received -> position sent, by the server

    @property
    def next_seq(self) -> int:
        return len(self.frames) + self.skipped

    def ready(self) -> Event:
        return {
            "event": "ready",
            "next_seq": self.next_seq,
            "max_fps": self.max_fps,
            "started": self.motion is not None,
        }

    def handle(self, message: Any) -> list[Event]:
        """Events answering one decoded JSON message (never raises for bad input)."""
        try:
            return self._dispatch(message)
        except ProtocolError as error:
            self.errors += 1
            return [error_event(error)]

    def _dispatch(self, message: Any) -> list[Event]:
        kind = message.get("type") if isinstance(message, dict) else None
        if kind == "frame":
            return self._frame(message)
        if kind == "frames":
            return self._batch(message)
        if kind == "start":
            return self._start(message)
        if kind == "end":
            return self.end()
        raise ProtocolError(
            "bad-message", "send a JSON object with type start, frame, frames or end"
        )

    def _start(self, message: dict[str, Any]) -> list[Event]:
        header = message.get("header")
        if not isinstance(header, str) or len(header) > MAX_HEADER_BYTES:
            raise ProtocolError("bad-header", "'start' needs the BVH header text ('header')")
        try:
            motion = read(header.encode(), max_values=0)
            if self.motion is not None:  # a reconnect: the skeleton must not change
                same = motion.skeleton.names == self.motion.skeleton.names
                if not same or motion.skeleton.n_channels != self.motion.skeleton.n_channels:
                    raise ProtocolError("bad-header", "the skeleton differs from this session's")
                return [self.ready()]
            self.aligner = LiveAligner(self.model, motion.skeleton, motion.fps, self.options)
        except (BVHError, AnalysisInputError) as error:
            raise ProtocolError("bad-header", " ".join(str(error).split())) from None
        self.motion = motion
        return [self.ready()]

    def _frame(self, message: dict[str, Any]) -> list[Event]:
        self._check_started()
        seq = _seq(message)
        if seq < self.next_seq:
            raise ProtocolError("duplicate", f"frame {seq} was already received", seq)
        if seq > self.next_seq:
            raise ProtocolError(
                "out-of-order", f"frame {seq} arrived; expected frame {self.next_seq}", seq
            )
        return self._take(message.get("values", message.get("line")), seq)

    def _batch(self, message: dict[str, Any]) -> list[Event]:
        self._check_started()
        first, frames = _seq(message), message.get("frames")
        if not isinstance(frames, list) or not 0 < len(frames) <= MAX_BATCH:
            text = f"a batch needs 'frames': a list of 1 to {MAX_BATCH} frames"
            raise ProtocolError("bad-frame", text, first)
        return self.take_batch(first, frames)

    def take_batch(self, first: int, frames: Sequence[Any] | FloatArray) -> list[Event]:
        """Frames ``first``, ``first + 1``, … (lists of numbers, BVH lines, or the rows of a
        binary message): a batch after the next expected frame is refused whole, frames already
        received are skipped with one ``duplicate`` error, each other frame is kept and aligned
        or gets its own error."""
        self._check_started()
        if first > self.next_seq:
            text = f"a batch from frame {first} arrived; expected frame {self.next_seq}"
            raise ProtocolError("out-of-order", text, first)
        events: list[Event] = []
        known = self.next_seq - first
        if known > 0:
            self.errors += 1
            last = first + min(known, len(frames)) - 1
            text = f"frames {first} to {last} were already received"
            events.append(error_event(ProtocolError("duplicate", text, first)))
        checked = self._checked_rows(frames)
        for offset in range(max(known, 0), len(frames)):
            try:
                raw = frames[offset]
                if checked is not None and checked[offset]:
                    events.extend(self._keep(raw, first + offset))
                else:
                    events.extend(self._take(raw, first + offset))
            except ProtocolError as error:
                self.errors += 1
                self.skipped += 1
                events.append(error_event(error))
        return events

    def _check_started(self) -> None:
        if self.motion is None or self.aligner is None or self.ended:
            raise ProtocolError("not-started", "send 'start' with the BVH header before frames")

    def _checked_rows(self, frames: Sequence[Any] | FloatArray) -> npt.NDArray[np.bool_] | None:
        """For the rows of a binary message ((frames, channels) numbers): which hold the
        skeleton's count of finite values, checked for the whole message in one call (each
        row's own check costs more than the row's other work); None for a JSON batch."""
        assert self.aligner is not None
        if not isinstance(frames, np.ndarray) or frames.ndim != 2:
            return None
        if frames.shape[1] != self.aligner.n_channels:
            return np.zeros(frames.shape[0], dtype=bool)  # each row gets `parse_values`' error
        return np.asarray(np.isfinite(frames).all(axis=1), dtype=np.bool_)

    def _take(self, raw: Any, seq: int) -> list[Event]:
        """Check one frame's values and the limits, keep it, align it."""
        assert self.aligner is not None
        return self._keep(parse_values(raw, self.aligner.n_channels, seq), seq)

    def _keep(self, values: FloatArray, seq: int) -> list[Event]:
        """The limits for one frame of checked values (C,), then keep it and align it."""
        assert self.motion is not None and self.aligner is not None
        if (len(self.frames) + 1) * values.size > MAX_VALUES:
            raise ProtocolError("too-long", "the session holds as many frames as it can: end it")
        if not self.limit.allow():
            self.dropped += 1
            raise ProtocolError("rate-limit", f"over {self.max_fps:g} frames/s: dropped", seq)
        self.frames.append(values)
        return self.aligner.push(values)

    def end(self) -> list[Event]:
        """Finish the session: the last repetition (if any) and the summary."""
        if self.ended:
            raise ProtocolError("ended", "the session has ended")
        self.ended = True
        if self.aligner is None:
            return [self.summary_only()]
        events = self.aligner.finish()
        events[-1].update(dropped=self.dropped, errors=self.errors)
        return events

    def summary_only(self) -> Event:
        return {"event": "summary", "repetitions": 0, "frames": 0, "latency_ms_p95": 0.0,
                "recording": None, "dropped": self.dropped, "errors": self.errors}  # fmt: skip

    def bvh(self) -> str | None:
        """The frames received as one BVH text (None without frames)."""
        if self.motion is None or not self.frames:
            return None
        return dumps(self.motion.with_frames(np.vstack(self.frames)))
