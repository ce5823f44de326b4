"""Is a recording plausible enough to analyse? One check before any analysis allocates anything.

`check_recording` works on a parsed `Motion` (its header and frames, before any resampling) and
refuses, with `ImplausibleRecordingError` and a message in plain words saying what is wrong and
what to do:

- a frame time outside what capture systems produce (`Limits.min_frame_time` to
  `Limits.max_frame_time`: 1000 to 10 frames per second); a ``Frame Time: 1000`` header is a
  damaged file, not a 17-minute-per-frame recording, and resampling it would need millions of
  frames;
- no frames at all, or more frames or a longer duration than the configured maxima
  (`Limits.max_frames`, `Limits.max_seconds`);
- values far outside any human movement (`Limits.max_abs_value`: positions in any unit up to
  millimetres, rotations in degrees, stay far below it);
- an analysis whose memory estimate exceeds `Limits.max_analysis_bytes`. The estimate counts the
  recording's frames at its own rate on its own joints (reading, mapping onto the exercise's
  skeleton: `OWN_BYTES_PER_JOINT_FRAME`; a 30,210-frame, 60-joint Rokoko take peaked 186 bytes per
  joint and frame above its start in `map_onto`) and the frames after resampling to the model's
  frame rate on the model's joints (every later stage: `BYTES_PER_JOINT_FRAME`; a 41,120-frame,
  22-joint UI-PRMD run peaked 486 MB above its start, 540 bytes per joint and frame), each with a
  margin of about a fifth.

The upload form and API (`webapp.recordings.uploads`), the command line and the worker call it;
`analysis.pipeline.analyse` calls it too (through `prepare`), so no caller can skip it. Callers
pass their own `Limits` (the web app from its settings); the defaults are in `Limits`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from analysis.bvh.errors import AnalysisInputError
from analysis.bvh.io import Motion

BYTES_PER_JOINT_FRAME = 640
OWN_BYTES_PER_JOINT_FRAME = 224
_TOLERANCE = 1e-6  # a header rounded to 6 decimals (0.033333) must not fall off an edge


class ImplausibleRecordingError(AnalysisInputError):
    """The recording's header or values are outside what a capture system produces, or its
    analysis would need more time or memory than allowed (the message says which, in plain words).
    Trying again cannot help: the file itself must change."""


@dataclass(frozen=True)
class Limits:
    """What a recording may be. Times in seconds, memory in bytes."""

    min_frame_time: float = 0.001
    max_frame_time: float = 0.1
    max_seconds: float = 1800.0
    max_frames: int = 500_000
    max_analysis_bytes: int = 2 << 30
    max_abs_value: float = 1e6

    @classmethod
    def from_settings(cls, settings: object) -> Limits:
        """Limits from a settings object's ``RECORDING_MAX_SECONDS``, ``RECORDING_MAX_FRAMES``
        and ``RECORDING_MAX_ANALYSIS_BYTES`` (the web app's); a missing one keeps its default."""
        default = cls()
        return cls(
            max_seconds=float(getattr(settings, "RECORDING_MAX_SECONDS", default.max_seconds)),
            max_frames=int(getattr(settings, "RECORDING_MAX_FRAMES", default.max_frames)),
            max_analysis_bytes=int(
                getattr(settings, "RECORDING_MAX_ANALYSIS_BYTES", default.max_analysis_bytes)
            ),
        )


DEFAULT_LIMITS = Limits()


def check_recording(
    motion: Motion,
    model_fps: float | None = None,
    model_joints: int | None = None,
    limits: Limits = DEFAULT_LIMITS,
) -> None:
    """Raise `ImplausibleRecordingError` if ``motion`` should not be analysed (see the module
    docstring). Without ``model_fps`` / ``model_joints`` (an upload whose exercise is not known
    yet) the memory estimate counts the recording's own frames only (reading and mapping)."""
    check_frame_time(motion.frame_time, limits)
    check_size(motion.n_frames, motion.duration, limits)
    check_values(motion, limits)
    check_memory(motion, model_fps, model_joints, limits)


def check_frame_time(frame_time: float, limits: Limits) -> None:
    low, high = limits.min_frame_time, limits.max_frame_time
    if low * (1 - _TOLERANCE) <= frame_time <= high * (1 + _TOLERANCE):
        return
    raise ImplausibleRecordingError(
        f"The file says each frame lasts {frame_time:g} s ({1.0 / frame_time:g} frames per "
        f"second); motion capture records between {1.0 / high:g} and {1.0 / low:g} frames per "
        "second, so the file's frame time is wrong. Export the recording again from the capture "
        "software."
    )


def check_size(n_frames: int, seconds: float, limits: Limits) -> None:
    if n_frames == 0:
        raise ImplausibleRecordingError(
            "The file holds no movement (0 frames). Export the recording again from the capture "
            "software."
        )
    if n_frames > limits.max_frames:
        raise ImplausibleRecordingError(
            f"The recording has {n_frames:,} frames; at most {limits.max_frames:,} can be "
            "analysed. Cut it into shorter takes and upload them one by one."
        )
    if seconds > limits.max_seconds:
        longest, this = distinct_durations(limits.max_seconds, seconds)
        raise ImplausibleRecordingError(
            f"The recording lasts {this}; at most {longest} can be analysed. Cut it into "
            "shorter takes and upload them one by one."
        )


def check_values(motion: Motion, limits: Limits) -> None:
    frames = motion.frames
    if frames.size == 0:
        return
    largest = np.abs(frames).max(axis=1)
    bad = np.flatnonzero(~(largest <= limits.max_abs_value))
    if bad.size == 0:
        return
    frame = int(bad[0])
    raise ImplausibleRecordingError(
        f"The recording holds values far outside any human movement (frame {frame + 1} has "
        f"{float(largest[frame]):g}); the file is damaged. Export it again from the capture "
        "software."
    )


def analysis_bytes(motion: Motion, model_fps: float | None, model_joints: int | None) -> int:
    """Estimated peak memory of analysing ``motion`` (bytes): see the module docstring; without
    the model's frame rate and joints, only the part at the recording's own rate."""
    own = motion.n_frames * max(len(motion.skeleton.names), 1) * OWN_BYTES_PER_JOINT_FRAME
    if model_fps is None or model_joints is None:
        return own
    at_model_rate = math.ceil(motion.duration * model_fps) + 1
    return own + at_model_rate * max(model_joints, 1) * BYTES_PER_JOINT_FRAME


def check_memory(
    motion: Motion, model_fps: float | None, model_joints: int | None, limits: Limits
) -> None:
    needed = analysis_bytes(motion, model_fps, model_joints)
    if needed <= limits.max_analysis_bytes:
        return
    raise ImplausibleRecordingError(
        f"Analysing this recording would need about {_bytes_text(needed)} of memory; at most "
        f"{_bytes_text(limits.max_analysis_bytes)} are allowed. Upload a shorter take (it lasts "
        f"{duration_text(motion.duration)})."
    )


def _bytes_text(n_bytes: float) -> str:
    if n_bytes >= 1 << 30:
        return f"{n_bytes / (1 << 30):.1f} GB"
    return f"{n_bytes / (1 << 20):.0f} MB"


def duration_text(seconds: float, decimals: int = 1) -> str:
    """A duration people read: '0.6 s', '2 min 5 s', '1 h 3 min'."""
    if seconds < 60:
        return f"{seconds:.{decimals}f} s"
    if seconds < 3600:
        minutes, rest = divmod(seconds, 60)
        return f"{int(minutes)} min {rest:.0f} s" if round(rest) else f"{int(minutes)} min"
    hours, rest = divmod(seconds, 3600)
    return f"{int(hours)} h {int(rest // 60)} min"


def distinct_durations(a: float, b: float) -> tuple[str, str]:
    """``a`` and ``b`` as `duration_text` with just enough decimals that two different values
    never print the same (a 0.63 s take is not refused for lasting '0.6 s' when '0.6 s' is
    needed)."""
    for decimals in range(1, 4):
        texts = duration_text(a, decimals), duration_text(b, decimals)
        if texts[0] != texts[1] or a == b:
            return texts
    return f"{a:.6g} s", f"{b:.6g} s"
