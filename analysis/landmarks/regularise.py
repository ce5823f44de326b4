"""Regularising refined landmarks against the training sequences (ours, beside thesis 004 §5.5).

- `regularise`: grammar-constrained typing of the refined landmarks by dynamic programming: keep,
  retype, drop or insert landmarks so that consecutive types follow the transitions seen in the
  training sequences, at the least pose cost.
- `relocate`: landmark types that the training data shows at the pose farthest from the
  preceding landmark (an "end of range") are moved to that pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
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


@nb.njit(cache=True, nogil=True)
def _tempo_cost(gap: float, typical: float, tempo: float, short: float) -> float:
    """`tempo_costs` of one type pair (the same operations, so the same bits)."""
    limit = short * typical
    shortfall = 1.0 - gap / limit if limit > 0 else 0.0
    return tempo * min(max(shortfall, 0.0), 1.0)


@nb.njit(cache=True, nogil=True)
def _lesser(a: float, b: float) -> float:
    """``np.minimum`` of two numbers: NaN when either is."""
    if np.isnan(a) or np.isnan(b):
        return np.nan
    return a if a <= b else b


@nb.njit(cache=True, nogil=True)
def _bridges(  # noqa: PLR0917 - numba functions take positional arguments only
    distances: FloatArray, first: int, last: int, allowed: npt.NDArray[np.bool_], insert: float,
    cost: FloatArray, kind: IntArray, where: IntArray,
) -> None:  # fmt: skip
    """Cost (width, width), type and frame of the best landmark to insert strictly between frames
    ``first`` and ``last``, between a landmark of type a (row) and one of type b (column), for
    a → σ → b allowed: the frame closest to σ's tutor mean, at ``insert`` plus its pose cost
    (`pose_costs`). Written into ``cost`` (inf), ``kind`` and ``where`` (−1) where none."""
    width = allowed.shape[0]
    cost[:] = np.inf
    kind[:] = -1
    where[:] = -1
    if last - first - 1 <= 0:
        return
    for sigma in range(width):
        at = first + 1  # np.argmin: the first smallest, the first NaN if any
        for frame in range(first + 2, last):
            value = distances[frame, sigma]
            if np.isnan(distances[at, sigma]):
                break
            if value < distances[at, sigma] or np.isnan(value):
                at = frame
        lowest = distances[at, 0]  # the frame's smallest distance over types, NaN if any is
        for t in range(1, width):
            lowest = _lesser(lowest, distances[at, t])
        price = insert + (distances[at, sigma] - lowest)
        for a in range(width):
            for b in range(width):
                if allowed[a, sigma] and allowed[sigma, b] and price < cost[a, b]:
                    cost[a, b], kind[a, b], where[a, b] = price, sigma, at


@nb.njit(cache=True, nogil=True)
def _relax(  # noqa: PLR0917
    frames: IntArray, cost: FloatArray, distances: FloatArray, allowed: npt.NDArray[np.bool_],
    weights: FloatArray, gaps: FloatArray, best: FloatArray, back: npt.NDArray[np.int64],
    j: int, k: int, scratch: tuple[FloatArray, IntArray, IntArray, FloatArray],
) -> None:  # fmt: skip
    """Improve best[k] through landmark j kept before k (those between dropped); ``weights``:
    insert, delete, tempo and short of `GrammarOptions`; ``gaps`` (width, width) or empty."""
    width = allowed.shape[0]
    insert, delete, tempo, short = weights[0], weights[1], weights[2], weights[3]
    via, kind, where, total = scratch
    first, last = int(frames[j]), int(frames[k])
    _bridges(distances, first, last, allowed, insert, via, kind, where)
    paced = gaps.size > 0 and tempo > 0
    gap = float(last - first)
    dropped = delete * (k - j - 1)
    direct = np.empty((width, width))
    for a in range(width):
        for b in range(width):
            direct[a, b] = 0.0 if allowed[a, b] else np.inf
            if paced:
                direct[a, b] = direct[a, b] + _tempo_cost(gap, gaps[a, b], tempo, short)
                # a bridged pair a → σ → b: half the span on each side of the inserted landmark
                sigma = max(kind[a, b], 0)
                half = 0.0
                if kind[a, b] >= 0:
                    half = _tempo_cost(gap / 2.0, gaps[a, sigma], tempo, short) + _tempo_cost(
                        gap / 2.0, gaps[sigma, b], tempo, short
                    )
                via[a, b] = via[a, b] + half
            total[a, b] = best[j, a] + _lesser(direct[a, b], via[a, b]) + dropped
    for b in range(width):
        src = 0  # np.argmin over the previous type: the first smallest, the first NaN if any
        for a in range(1, width):
            if np.isnan(total[src, b]):
                break
            if total[a, b] < total[src, b] or np.isnan(total[a, b]):
                src = a
        value = total[src, b] + cost[k, b]
        if value < best[k, b]:
            bridged = via[src, b] < direct[src, b]
            best[k, b] = value
            back[k, b, 0], back[k, b, 1] = j, src
            back[k, b, 2] = kind[src, b] if bridged else -1
            back[k, b, 3] = where[src, b] if bridged else -1


@nb.njit(cache=True, nogil=True)
def _lattice(  # noqa: PLR0917
    frames: IntArray, cost: FloatArray, distances: FloatArray, allowed: npt.NDArray[np.bool_],
    weights: FloatArray, gaps: FloatArray, lookback: int, best: FloatArray,
    back: npt.NDArray[np.int64],
) -> None:  # fmt: skip
    """The dynamic programme of `regularise`: best[k, t] is the least cost of a sequence whose
    last kept landmark is k with type t; back[k, t] = (previous landmark, its type, inserted
    type, inserted frame), −1 where none."""
    width = allowed.shape[0]
    scratch = (
        np.empty((width, width)),
        np.empty((width, width), np.int64),
        np.empty((width, width), np.int64),
        np.empty((width, width)),
    )
    for k in range(1, frames.size):
        for j in range(max(0, k - lookback - 1), k):
            _relax(frames, cost, distances, allowed, weights, gaps, best, back, j, k, scratch)


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
    weights = np.array([options.insert, options.delete, options.tempo, options.short])
    typical = np.zeros((0, 0)) if gaps is None else np.ascontiguousarray(gaps, dtype=np.float64)
    frames = np.ascontiguousarray(landmarks.frames, dtype=np.int64)
    _lattice(frames, cost, distances, allowed, weights, typical, options.lookback, best, back)
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
