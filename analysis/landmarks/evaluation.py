"""Evaluation of identified landmarks (paper 004, section 5.6.1, eqs 5.34–5.36).

Every ground-truth landmark gets a compromise interval [Λ0, Λ1] of frames whose pose is within
Δ_Λ of the way to the neighbouring landmark (eq 5.34). A detected landmark is a true positive when
it lies in the interval of a ground-truth landmark of the same type; each ground-truth landmark
matches at most one detection (the thesis counts the other matches as false positives, 5.6.2).

Counting true negatives: eq 5.35 writes tn = |χ̄| − tp − fp − fn, which is −fn for the refined set
χ̄ (tp + fp = |χ̄|). We read |χ| as eq 5.23 defines it, one observation per testing frame, so
tn = n_frames − tp − fp − fn (the frames rightly left without a landmark). That makes the accuracy
of eq 5.36 close to 1 whenever n_frames ≫ errors, so `Confusion.strict_accuracy`, tp / (tp + fp +
fn) (the same ratio with tn = 0), is reported beside it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True)
class Confusion:
    """Counts of eq 5.35 for one sample (or summed over samples)."""

    tp: int
    fp: int
    fn: int
    tn: int

    @property
    def precision(self) -> float:
        """π (eq 5.36): tp / (tp + fp); 0 when nothing was detected."""
        return self.tp / (self.tp + self.fp) if self.tp + self.fp else 0.0

    @property
    def accuracy(self) -> float:
        """α (eq 5.36): (tp + tn) / (tp + tn + fp + fn)."""
        total = self.tp + self.tn + self.fp + self.fn
        return (self.tp + self.tn) / total if total else 1.0

    @property
    def strict_accuracy(self) -> float:
        """tp / (tp + fp + fn): α without true negatives (1 when there is nothing to find)."""
        total = self.tp + self.fp + self.fn
        return self.tp / total if total else 1.0


def _extent(distance: FloatArray, limit: float) -> int:
    """How many frames from the start of ``distance`` stay within ``limit`` without a break."""
    outside = np.flatnonzero(distance > limit)
    return int(outside[0]) if outside.size else int(distance.size)


def compromise_intervals(data: FloatArray, frames: npt.ArrayLike, delta: float = 0.15) -> IntArray:
    """Eq 5.34: [Λ0, Λ1] (inclusive frames) of each ground-truth landmark: (n, 2) ints.

    data: (F, D) motion data M (e.g. positions in cm, flattened); frames: (n,) increasing landmark
    frames; delta: Δ_Λ (0.15 for identification). The neighbours of the first and last landmark are
    the first and last frame. Distances are taxicab (L1) norms over the D columns.
    """
    m = np.asarray(data, dtype=np.float64).reshape(len(data), -1)
    f = np.asarray(frames, dtype=np.int64)
    bounds = np.concatenate([[0], f, [m.shape[0] - 1]])
    out = np.empty((f.size, 2), dtype=np.int64)
    for i, frame in enumerate(f):
        prev, nxt = bounds[i], bounds[i + 2]
        here = m[frame]
        left = np.abs(m[prev : frame + 1][::-1] - here).sum(axis=1)  # from the landmark backwards
        right = np.abs(m[frame : nxt + 1] - here).sum(axis=1)
        left_limit = np.abs(here - m[prev]).sum() * delta
        right_limit = np.abs(here - m[nxt]).sum() * delta
        out[i, 0] = frame - (_extent(left, left_limit) - 1)
        out[i, 1] = frame + (_extent(right, right_limit) - 1)
    return out


def match(
    frames: npt.ArrayLike, types: npt.ArrayLike, gt_types: npt.ArrayLike, intervals: IntArray
) -> IntArray:
    """One-to-one matching of detections to ground-truth intervals of the same type.

    Returns (n_detections,) the matched ground-truth index or −1. Per type, ground truths are taken
    by increasing interval end, each matched to the earliest unused detection inside it (this greedy
    order gives the largest number of matches for points and intervals).
    """
    f = np.asarray(frames, dtype=np.int64)
    t = np.asarray(types, dtype=np.int64)
    gt = np.asarray(gt_types, dtype=np.int64)
    owner = np.full(f.size, -1, dtype=np.int64)
    for j in np.lexsort((intervals[:, 0], intervals[:, 1])):
        free = np.flatnonzero(
            (owner < 0) & (t == gt[j]) & (f >= intervals[j, 0]) & (f <= intervals[j, 1])
        )
        if free.size:
            owner[free[np.argmin(f[free])]] = j
    return owner


def confusion(
    frames: npt.ArrayLike,
    types: npt.ArrayLike,
    gt_types: npt.ArrayLike,
    intervals: IntArray,
    n_frames: int,
) -> Confusion:
    """Eq 5.35: tp, fp, fn and tn of detected landmarks against ground truth with intervals."""
    owner = match(frames, types, gt_types, intervals)
    tp = int(np.sum(owner >= 0))
    fp = int(owner.size - tp)
    fn = int(len(intervals) - tp)
    return Confusion(tp, fp, fn, max(n_frames - tp - fp - fn, 0))


def evaluate(
    frames: npt.ArrayLike,
    types: npt.ArrayLike,
    gt_frames: npt.ArrayLike,
    gt_types: npt.ArrayLike,
    data: FloatArray,
    *,
    delta: float = 0.15,
) -> Confusion:
    """Compromise intervals of the ground truth on ``data`` (F, D), then `confusion`."""
    intervals = compromise_intervals(data, gt_frames, delta)
    return confusion(frames, types, gt_types, intervals, len(data))


def summed(items: list[Confusion]) -> Confusion:
    """The element-wise sum of several confusions."""
    return Confusion(*(int(sum(getattr(c, k) for c in items)) for k in ("tp", "fp", "fn", "tn")))
