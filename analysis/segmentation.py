"""Repetition boundaries from the main movement axis of the tutor (a fast, robust segmenter).

The tutor's movement relative to its starting pose is summarised by its first principal component:
the *progress* signal rises from the start pose to the end of range and falls back. Projecting a
patient's pose features on the same axis gives their progress signal; each prominent peak is one
repetition's end of range and the lowest point between two peaks is where one repetition ends and
the next begins. Peak distance and prominence come from the tutor's own tempo and range, relaxed so
that slower patients and a reduced range of motion still count.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.signal import find_peaks

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class ProgressAxis:
    """Mean start pose and unit movement direction in feature space; progress of the tutor's
    end-of-range poses is about 1."""

    start_pose: FloatArray
    direction: FloatArray
    scale: float
    rep_frames: float

    def progress(self, features: FloatArray) -> FloatArray:
        """Progress signal of (F, D) feature rows: (F,), 0 at the start pose, ~1 at end of range."""
        return (features - self.start_pose) @ self.direction / self.scale


def fit_axis(features: FloatArray, starts: IntArray, peaks: IntArray) -> ProgressAxis:
    """The progress axis of a tutor from its feature rows and its start / end-of-range frames."""
    start_pose = features[starts].mean(axis=0)
    moved = features - start_pose
    _, _, vt = np.linalg.svd(moved - moved.mean(axis=0), full_matrices=False)
    direction = vt[0]
    if np.mean(moved[peaks] @ direction) < 0:
        direction = -direction
    scale = float(np.mean(moved[peaks] @ direction)) or 1.0
    rep_frames = float(np.median(np.diff(starts))) if starts.size > 1 else float(features.shape[0])
    return ProgressAxis(start_pose, direction, scale, rep_frames)


@dataclass(frozen=True, eq=False)
class Segments:
    """Repetition starts (R,), ends (R,) and end-of-range frames (R,) in recording frames."""

    starts: IntArray
    ends: IntArray
    peaks: IntArray


def _smooth(signal: FloatArray, width: int) -> FloatArray:
    if width < 2 or signal.size < width:
        return signal
    kernel = np.hanning(width + 2)[1:-1]
    padded = np.pad(signal, width, mode="edge")
    return np.convolve(padded, kernel / kernel.sum(), mode="same")[width:-width]


def segment(progress: FloatArray, rep_frames: float, min_range: float = 0.3) -> Segments:
    """Cut a progress signal into repetitions (see the module docstring)."""
    smooth = _smooth(progress, max(int(rep_frames / 12), 1))
    span = float(np.percentile(smooth, 98) - np.percentile(smooth, 2)) if smooth.size else 0.0
    prominence = max(min_range * span, 0.15)
    peaks, _ = find_peaks(smooth, distance=max(int(0.45 * rep_frames), 1), prominence=prominence)
    if peaks.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return Segments(empty, empty, empty)
    cuts = [int(np.argmin(smooth[a:b])) + a for a, b in itertools.pairwise(peaks)]
    first = _boundary_before(smooth, int(peaks[0]), rep_frames)
    last = _boundary_after(smooth, int(peaks[-1]), rep_frames)
    starts = np.array([first, *cuts], dtype=np.int64)
    ends = np.array([*(c - 1 for c in cuts), last], dtype=np.int64)
    return Segments(starts, np.maximum(ends, starts), peaks.astype(np.int64))


def _boundary_before(signal: FloatArray, peak: int, rep_frames: float) -> int:
    """Where the first repetition leaves the rest pose: the last low point before its peak."""
    lo = max(0, peak - int(1.5 * rep_frames))
    window = signal[lo : peak + 1]
    floor = window.min() + 0.02 * (signal[peak] - window.min())
    below = np.flatnonzero(window <= floor)
    return lo + int(below[-1]) if below.size else lo


def _boundary_after(signal: FloatArray, peak: int, rep_frames: float) -> int:
    """Where the last repetition is back at rest: the first low point after its peak."""
    hi = min(signal.size, peak + int(1.5 * rep_frames) + 1)
    window = signal[peak:hi]
    floor = window.min() + 0.02 * (signal[peak] - window.min())
    below = np.flatnonzero(window <= floor)
    return peak + int(below[0]) if below.size else hi - 1
