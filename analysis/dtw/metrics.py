"""How well two motions are aligned, and how similar they are, reported separately (003 ch. 4).

Alignment quality:

- ``kendall_tau_score``: mean Kendall tau between corresponding displacement-vector components of
  the two aligned motions (003 eqs 2.9 and 5.13); the best alignment metric of 003's study.
- ``pearson_score``: mean Pearson correlation of the aligned feature curves (001 eq 18).
- ``segment_agreement``: share of aligned frame pairs in the same movement segment (000, 1 - eq 5).
- ``mapping_deviation``: per query frame, |on-line reference index - offline path's index| in
  frames, with the summaries of 003 eqs 5.14-5.16.

Similarity (pose distance, lower is more similar): ``pose_distance`` angular (003 eq 3.1,
(2/pi) arccos|q.q'| per joint) or positional (003 eq 3.2, per-joint Euclidean distance of
root-relative positions), averaged over aligned frames.

Motions are (frames, joints, 4) unit quaternions (w, x, y, z) or (frames, joints, 3) positions; a
``path`` (K, 2) of (i, j) pairs pairs them up (default: frame k with frame k, equal lengths).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.dtw.frame_costs import paired_costs
from analysis.kinematics import quaternions as quat

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
CONSTANT_TOL = 1e-5  # a curve varying less than this is constant (003 4.3.4: rounding noise)


def _pairs(
    a: FloatArray, b: FloatArray, path: npt.ArrayLike | None
) -> tuple[FloatArray, FloatArray]:
    if path is None:
        if len(a) != len(b):
            raise ValueError(
                f"without a path both motions need equal lengths ({len(a)} != {len(b)})"
            )
        return a, b
    p = np.asarray(path, dtype=np.int64)
    return a[p[:, 0]], b[p[:, 1]]


def displacement_vectors(rotations: npt.ArrayLike) -> FloatArray:
    """Joint rotations (..., 4) as the unit vector they turn +y into (003 eq 2.9): (..., 3)."""
    q = np.asarray(rotations, dtype=np.float64)
    return quat.rotate(q, np.broadcast_to([0.0, 1.0, 0.0], (*q.shape[:-1], 3)))


def _correlations(A: FloatArray, B: FloatArray, method: str) -> FloatArray:
    """Correlation per column of A, B (K, c); both constant -> 1, one constant -> 0."""
    flat_a = np.ptp(A, axis=0) <= CONSTANT_TOL
    flat_b = np.ptp(B, axis=0) <= CONSTANT_TOL
    out = np.where(flat_a & flat_b, 1.0, 0.0)
    varying = ~(flat_a | flat_b)
    if not varying.any():
        return out
    if method == "kendall":
        out[varying] = kendall_tau_b(A[:, varying], B[:, varying])
    else:
        for c in np.flatnonzero(varying):
            out[c] = np.corrcoef(A[:, c], B[:, c])[0, 1]
    return out


def kendall_tau_b(A: FloatArray, B: FloatArray, block: int = 64) -> FloatArray:
    """Kendall's tau-b of every column pair of A, B (K, c) at once (as scipy's ``kendalltau``,
    ties included): Σ sgn(Δa)·sgn(Δb) over all pairs of rows, over the square root of the
    products of the untied pair counts. ``block`` is kept for callers of the former numpy
    version (rows taken that many at a time); the compiled counts need no blocks."""
    del block
    counts = _pair_counts(np.ascontiguousarray(A, dtype=np.float64),
                          np.ascontiguousarray(B, dtype=np.float64))  # fmt: skip
    concordance, untied_a, untied_b = counts[0], counts[1], counts[2]
    return np.asarray(concordance / np.sqrt(np.maximum(untied_a * untied_b, 1e-300)))


@nb.njit(cache=True, nogil=True)
def _pair_counts(A: FloatArray, B: FloatArray) -> FloatArray:
    """(3, c): per column, Σ sgn(Δa)·sgn(Δb) and the untied pair counts of A and of B, over the
    ordered pairs of different rows (each unordered pair twice, as the former numpy sums
    counted them). Whole numbers, so the order of the sums cannot change a bit."""
    K, c = A.shape
    out = np.zeros((3, c))
    for col in range(c):
        concordant, tied_a, tied_b = 0, 0, 0
        for i in range(K):
            a, b = A[i, col], B[i, col]
            for j in range(i + 1, K):
                da, db = a - A[j, col], b - B[j, col]
                sa = (da > 0.0) - (da < 0.0)
                sb = (db > 0.0) - (db < 0.0)
                concordant += sa * sb
                tied_a += sa == 0
                tied_b += sb == 0
        pairs = K * (K - 1) // 2
        out[0, col] = 2.0 * concordant
        out[1, col] = 2.0 * (pairs - tied_a)
        out[2, col] = 2.0 * (pairs - tied_b)
    return out


def kendall_tau_score(
    a_rot: npt.ArrayLike, b_rot: npt.ArrayLike, path: npt.ArrayLike | None = None
) -> float:
    """003 eq 5.13: mean Kendall tau over joints and x, y, z of the displacement vectors.

    a_rot, b_rot: (frames, joints, 4) local rotations. In [-1, 1]; 1 is a perfect alignment.
    """
    a, b = _pairs(np.asarray(a_rot, float), np.asarray(b_rot, float), path)
    va, vb = displacement_vectors(a), displacement_vectors(b)
    K = len(va)
    return float(_correlations(va.reshape(K, -1), vb.reshape(K, -1), "kendall").mean())


def pearson_score(a: npt.ArrayLike, b: npt.ArrayLike, path: npt.ArrayLike | None = None) -> float:
    """001 eq 18: mean Pearson correlation of the aligned curves; a, b: (frames, ...) features."""
    A, B = _pairs(np.asarray(a, float), np.asarray(b, float), path)
    K = len(A)
    return float(_correlations(A.reshape(K, -1), B.reshape(K, -1), "pearson").mean())


def segment_labels(n_frames: int, starts: npt.ArrayLike) -> IntArray:
    """Segment index per frame (n_frames,) from sorted 0-based segment start frames."""
    s = np.asarray(starts, dtype=np.int64)
    return np.searchsorted(s, np.arange(n_frames), side="right") - 1


def segment_agreement(
    path: npt.ArrayLike, labels_x: npt.ArrayLike, labels_y: npt.ArrayLike
) -> float:
    """Share of aligned pairs (i, j) with labels_x[i] == labels_y[j] (000: #CA / (#CA + #IA))."""
    p = np.asarray(path, dtype=np.int64)
    lx, ly = np.asarray(labels_x), np.asarray(labels_y)
    return float(np.mean(lx[p[:, 0]] == ly[p[:, 1]]))


def offline_mapping(path: npt.ArrayLike, n: int) -> FloatArray:
    """Reference index per query frame (n,) from a path: the mean of the frames it is matched to."""
    p = np.asarray(path, dtype=np.int64)
    total = np.bincount(p[:, 0], weights=p[:, 1].astype(float), minlength=n)
    count = np.bincount(p[:, 0], minlength=n)
    return total / np.maximum(count, 1)


@dataclass(frozen=True)
class Deviation:
    """Deviation of an on-line mapping from the offline path, in frames and normalised (003)."""

    median: float  # median |online - offline| over query frames, frames
    mean: float  # mean |online - offline|, frames
    max: float  # max |online - offline|, frames
    bias: float  # 003 eq 5.14: mean signed (offline - online) / n
    abs_avg: float  # 003 eq 5.15: mean |offline - online| / n
    max_norm: float  # 003 eq 5.16: max |offline - online| / n


def mapping_deviation(online: npt.ArrayLike, path: npt.ArrayLike) -> Deviation:
    """Compare an on-line mapping (n,) (reference index per query frame) with an offline path."""
    on = np.asarray(online, dtype=np.float64)
    n = len(on)
    diff = offline_mapping(path, n) - on
    ad = np.abs(diff)
    return Deviation(
        median=float(np.median(ad)),
        mean=float(ad.mean()),
        max=float(ad.max()),
        bias=float(diff.sum() / n**2),
        abs_avg=float(ad.sum() / n**2),
        max_norm=float(ad.max() / n),
    )


def pose_distance(
    a: npt.ArrayLike,
    b: npt.ArrayLike,
    kind: str = "angular",
    weights: npt.ArrayLike | None = None,
    path: npt.ArrayLike | None = None,
) -> float:
    """Mean weighted pose distance over aligned frames (003 eqs 3.1, 3.2); 0 for identical poses.

    angular: a, b (frames, joints, 4) rotations, per joint (2/pi) arccos|q.q'| in [0, 1].
    positional: a, b (frames, joints, 3) root-relative positions, per joint |p - p'| (their units).
    """
    A, B = _pairs(np.asarray(a, float), np.asarray(b, float), path)
    K, J = A.shape[0], A.shape[1]
    w = np.ones(J) if weights is None else np.asarray(weights, dtype=np.float64)
    if kind == "angular":
        per = paired_costs(A.reshape(K * J, 4), B.reshape(K * J, 4), "geodesic").reshape(K, J)
    elif kind == "positional":
        per = np.linalg.norm(A - B, axis=-1)
    else:
        raise ValueError(f"kind must be 'angular' or 'positional', got {kind!r}")
    return float((per @ w).mean())
