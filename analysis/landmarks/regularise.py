"""Regularising refined landmarks against the training sequences (ours, beside thesis 004 §5.5).

- `regularise`: grammar-constrained typing of the refined landmarks by dynamic programming: keep,
  retype, drop or insert landmarks so that consecutive types follow the transitions seen in the
  training sequences, at the least pose cost.
- `relocate`: landmark types that the training data shows at the pose farthest from the
  preceding landmark (an "end of range") are moved to that pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.landmarks.key_poses import KeyPoses

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def transitions(sequences: list[npt.ArrayLike], n_types: int) -> npt.NDArray[np.bool_]:
    """Which landmark type may follow which, from training sequences: (T + 1, T + 1) booleans
    indexed by type (row: previous, column: next; index 0 unused)."""
    allowed = np.zeros((n_types + 1, n_types + 1), dtype=bool)
    for seq in sequences:
        s = np.asarray(seq, dtype=np.int64)
        allowed[s[:-1], s[1:]] = True
    return allowed


def _spread(poses: FloatArray, origin: int, frames: IntArray) -> FloatArray:
    """Mean over joints of the distance of each pose in ``frames`` to the pose at ``origin``."""
    return np.linalg.norm(poses[frames] - poses[origin], axis=-1).mean(axis=-1)


def farthest_frame(poses: FloatArray, previous: int, following: int) -> int:
    """The frame strictly between two landmarks whose pose is farthest from the first one's.

    poses: (F, J, k) e.g. root-relative positions. Returns ``previous + 1`` when there is no room.
    """
    frames = np.arange(previous + 1, max(following, previous + 2), dtype=np.int64)
    frames = frames[frames < poses.shape[0]]
    return int(frames[np.argmax(_spread(poses, previous, frames))]) if frames.size else previous


def farthest_types(
    samples: list[tuple[FloatArray, IntArray, IntArray]], tolerance: int = 2, share: float = 0.8
) -> set[int]:
    """Landmark types that mark an extreme pose (ours): in the training samples (poses (F, J, k),
    frames, types), at least ``share`` of their landmarks lie within ``tolerance`` frames of the
    pose farthest from the preceding landmark (before the next one), e.g. an "end of range"."""
    hits: dict[int, list[bool]] = {}
    for poses, frames, types in samples:
        for k in range(1, len(frames) - 1):
            best = farthest_frame(poses, int(frames[k - 1]), int(frames[k + 1]))
            hits.setdefault(int(types[k]), []).append(abs(best - int(frames[k])) <= tolerance)
    return {t for t, h in hits.items() if np.mean(h) >= share}


def relocate(landmarks: KeyPoses, poses: FloatArray, types: set[int]) -> KeyPoses:
    """Move every inner landmark of the given types to the farthest pose from its predecessor
    (between its neighbours); the others stay. Returns landmarks sorted by frame."""
    frames = landmarks.frames.copy()
    for k in range(1, frames.size - 1):
        if int(landmarks.types[k]) in types:
            frames[k] = farthest_frame(poses, int(frames[k - 1]), int(frames[k + 1]))
    return KeyPoses(frames, landmarks.types.copy())


@dataclass(frozen=True)
class GrammarOptions:
    """Grammar-constrained typing of refined landmarks (ours).

    retype: cost of giving a landmark another type than the classifier's; delete: cost of dropping
    one; insert: cost of adding a missing landmark between two kept ones (plus its pose cost);
    lookback: how many landmarks in a row may be dropped at most; tempo, short: the tempo prior
    (`tempo_costs`, 0 = off), used when `regularise` is given the training's typical gaps.
    """

    retype: float = 0.5
    delete: float = 2.0
    insert: float = 0.5
    lookback: int = 4
    tempo: float = 0.0
    short: float = 0.5


def typical_gaps(samples: list[tuple[npt.ArrayLike, npt.ArrayLike]], n_types: int) -> FloatArray:
    """Median frames from a landmark of type a (row) to the next one of type b (column) in the
    training sequences [(frames, types)]: (T + 1, T + 1), 0 where the pair was never seen."""
    seen: dict[tuple[int, int], list[int]] = {}
    for frames, types in samples:
        f, t = np.asarray(frames, dtype=np.int64), np.asarray(types, dtype=np.int64)
        for k in range(1, f.size):
            seen.setdefault((int(t[k - 1]), int(t[k])), []).append(int(f[k] - f[k - 1]))
    out = np.zeros((n_types + 1, n_types + 1))
    for (a, b), gaps in seen.items():
        out[a, b] = float(np.median(gaps))
    return out


def tempo_costs(gap: float, gaps: FloatArray, options: GrammarOptions) -> FloatArray:
    """Cost (width, width) of two consecutive landmarks ``gap`` frames apart, by their types:
    tempo · (1 − gap / (short · typical gap)) when shorter than ``short`` times the typical gap,
    else 0 (ours: a repetition far quicker than any in training is more likely a pause's jitter
    read as key poses than a real one)."""
    limit = options.short * gaps
    with np.errstate(divide="ignore", invalid="ignore"):
        shortfall = np.where(limit > 0, 1.0 - gap / limit, 0.0)
    return options.tempo * np.clip(shortfall, 0.0, 1.0)


def pose_distances(signature: FloatArray, means: dict[int, FloatArray], width: int) -> FloatArray:
    """(F, width) squared distance per signature dimension of every frame to each type's tutor
    mean (eq 5.30); inf for types without a mean."""
    out = np.full((signature.shape[0], width), np.inf)
    for t, m in means.items():
        if t < width:
            out[:, t] = np.sum((signature - m) ** 2, axis=1) / max(signature.shape[1], 1)
    return out


def pose_costs(distances: FloatArray) -> FloatArray:
    """Cost of each frame as each type: `pose_distances` minus the frame's smallest one, so that a
    frame costs nothing as its best-fitting type (a patient far from every tutor pose is not
    dropped for that)."""
    return distances - distances.min(axis=1, keepdims=True)


def _bridges(
    distances: FloatArray, span: tuple[int, int], allowed: npt.NDArray[np.bool_], insert: float
) -> tuple[FloatArray, npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Cost (width, width), type and frame of the best landmark to insert strictly inside ``span``
    between a landmark of type a (row) and one of type b (column), for a → σ → b allowed: the
    frame closest to σ's tutor mean, at ``insert`` plus its pose cost."""
    width = allowed.shape[0]
    cost = np.full((width, width), np.inf)
    kind = np.full((width, width), -1, dtype=np.int64)
    where = np.full((width, width), -1, dtype=np.int64)
    inside = distances[span[0] + 1 : span[1]]
    if inside.shape[0] == 0:
        return cost, kind, where
    at = np.argmin(inside, axis=0)
    price = insert + pose_costs(inside)[at, np.arange(width)]
    for sigma in range(width):
        c = np.where(allowed[:, sigma][:, None] & allowed[sigma][None, :], price[sigma], np.inf)
        better = c < cost
        cost[better], kind[better], where[better] = c[better], sigma, span[0] + 1 + at[sigma]
    return cost, kind, where


@dataclass
class _Lattice:
    """Dynamic-programming state of `regularise`: best[k, t] is the least cost of a sequence whose
    last kept landmark is k with type t; back[k, t] = (previous landmark, its type, inserted
    type, inserted frame), −1 where none."""

    frames: IntArray
    cost: FloatArray  # (n, width) cost of keeping landmark k as type t
    distances: FloatArray  # (F, width) from `pose_distances`
    allowed: npt.NDArray[np.bool_]
    options: GrammarOptions
    best: FloatArray
    back: npt.NDArray[np.int64]
    gaps: FloatArray | None = None  # (width, width) typical gaps for the tempo prior


def _relax(lat: _Lattice, j: int, k: int) -> None:
    """Improve best[k] through landmark j kept before k (those between dropped)."""
    width = lat.allowed.shape[0]
    direct = np.where(lat.allowed, 0.0, np.inf)
    span = (int(lat.frames[j]), int(lat.frames[k]))
    via, kind, where = _bridges(lat.distances, span, lat.allowed, lat.options.insert)
    if lat.gaps is not None and lat.options.tempo > 0:
        gap = float(span[1] - span[0])
        direct = direct + tempo_costs(gap, lat.gaps, lat.options)
        # a bridged pair a → σ → b: half the span on each side of the inserted landmark
        half = tempo_costs(gap / 2.0, lat.gaps, lat.options)
        sigma = np.maximum(kind, 0)
        before, after = np.indices(kind.shape)
        via = via + np.where(kind >= 0, half[before, sigma] + half[sigma, after], 0.0)
    total = lat.best[j][:, None] + np.minimum(direct, via) + lat.options.delete * (k - j - 1)
    src, cols = np.argmin(total, axis=0), np.arange(width)
    value = total[src, cols] + lat.cost[k]
    better = value < lat.best[k]
    bridged = via[src, cols] < direct[src, cols]
    record = np.column_stack(
        [
            np.full(width, j),
            src,
            np.where(bridged, kind[src, cols], -1),
            np.where(bridged, where[src, cols], -1),
        ]
    )
    lat.best[k, better], lat.back[k, better] = value[better], record[better]


def regularise(
    landmarks: KeyPoses,
    signature: FloatArray,
    means: dict[int, FloatArray],
    allowed: npt.NDArray[np.bool_],
    options: GrammarOptions = GrammarOptions(),
    *,
    gaps: FloatArray | None = None,
) -> KeyPoses:
    """Keep, (re)type and complete refined landmarks so consecutive types follow ``allowed``.

    Minimises, by dynamic programming over (landmark, type): Σ pose cost (`pose_costs`) +
    retype · [type changed] over kept landmarks, + delete · dropped landmarks, + (insert + pose
    cost) per landmark inserted between two kept ones where the grammar needs one (at the frame
    closest to that type's tutor mean). A repetition's end of range detected as a start becomes an
    end of range again, and a missed one is put back, instead of a start being dropped.
    gaps: `typical_gaps` of the training sequences, for the tempo prior (+ `tempo_costs` per
    pair of consecutive kept landmarks) when ``options.tempo`` > 0.
    """
    n, width = landmarks.frames.size, allowed.shape[0]
    if n == 0:
        return landmarks
    distances = pose_distances(signature, means, width)
    retyped = np.arange(width)[None, :] != landmarks.types[:, None]
    cost = pose_costs(distances[landmarks.frames]) + options.retype * retyped
    best = cost + options.delete * np.arange(n)[:, None]  # k as the first kept landmark
    back = np.full((n, width, 4), -1, dtype=np.int64)
    lat = _Lattice(landmarks.frames, cost, distances, allowed, options, best, back, gaps)
    for k in range(1, n):
        for j in range(max(0, k - options.lookback - 1), k):
            _relax(lat, j, k)
    return _regularised(landmarks, best + options.delete * (n - 1 - np.arange(n))[:, None], back)


def _regularised(landmarks: KeyPoses, total: FloatArray, back: npt.NDArray[np.int64]) -> KeyPoses:
    k, t = (int(v) for v in np.unravel_index(int(np.argmin(total)), total.shape))
    out: list[tuple[int, int]] = []
    while k >= 0:
        out.append((int(landmarks.frames[k]), t))
        j, src, kind, frame = (int(v) for v in back[k, t])
        if kind >= 0:
            out.append((frame, kind))
        k, t = j, src
    out.sort()
    return KeyPoses(
        np.array([f for f, _ in out], dtype=np.int64), np.array([t for _, t in out], dtype=np.int64)
    )
