"""Landmark refining (paper 004, section 5.5, eqs 5.27–5.33).

Candidate landmarks come in bursts of neighbouring frames around each key pose. Refining groups
them into clusters (EM = Gaussian mixture, k-means, or the temporal rule T_c of eq 5.29) and keeps
one candidate per cluster: μ1 the member closest to the tutor's mean signature for its own type,
μ2 the member of the cluster's majority type closest to that type's tutor mean (eq 5.30).

EM and k-means cluster the candidates on (frame, signature values at the frame): the thesis's
Weka observations carry the frame number (Figure 5.6), and without it one cluster would gather the
same pose from every repetition. The frame is given in frames, not rescaled, so time dominates.
The number of clusters, when not given, is the number of runs of candidates separated by more
than β frames (k-means), or the Bayesian-information-criterion best of a few counts around it (EM,
standing in for Weka's cross-validated choice).

Ours, beside the thesis (see docs: eval_landmarks for what each one brings):

- "gap" clustering: a new cluster wherever two candidates are more than β frames apart (eq 5.29's
  ratio rule keeps evenly spaced single candidates in one cluster); "extreme" selection.
- `analysis.landmarks.regularise` retypes and relocates the refined landmarks.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt
from sklearn.cluster import KMeans
from sklearn.mixture import GaussianMixture

from analysis.landmarks.key_poses import KeyPoses

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
Clustering = Literal["em", "kmeans", "tc", "gap"]
Selection = Literal["mu1", "mu2", "extreme"]


@dataclass(frozen=True)
class RefineOptions:
    """clustering: "em", "kmeans", "tc" (eq 5.29's ratio rule) or "gap" (a new cluster wherever
    two consecutive candidates are more than β frames apart); selection: "mu1", "mu2" or
    "extreme"; beta: β in frames (Table 5.1: 12–15); n_clusters: fixed count for EM/k-means or
    None; em_span: how many counts on each side of the gap estimate EM tries."""

    clustering: Clustering = "em"
    selection: Selection = "mu1"
    beta: float = 12.0
    n_clusters: int | None = None
    em_span: int = 2
    seed: int = 0


def mean_poses(
    signature: FloatArray, frames: npt.ArrayLike, types: npt.ArrayLike
) -> dict[int, FloatArray]:
    """Eq 5.30: the mean signature row P̄ over the landmarks of each type: {type: (k,)}."""
    frames = np.asarray(frames, dtype=np.int64)
    types = np.asarray(types, dtype=np.int64)
    return {int(t): signature[frames[types == t]].mean(axis=0) for t in np.unique(types)}


def temporal_clusters(frames: npt.ArrayLike, beta: float) -> IntArray:
    """Eq 5.29: T_c, cluster ids 1, 2, … of frames sorted in time.

    A new cluster starts at χ_i (i ≥ 3) when (f_i − f_{i−1}) / (f_{i−1} − f_{i−2}) > β; χ_1 and χ_2
    always share the first cluster.
    """
    f = np.asarray(frames, dtype=np.float64)
    ids = np.ones(f.size, dtype=np.int64)
    if f.size < 3:
        return ids
    gaps = np.diff(f)
    ratio = gaps[1:] / np.maximum(gaps[:-1], 1e-12)
    ids[2:] += np.cumsum(ratio > beta)
    return ids


def gap_clusters(frames: npt.ArrayLike, beta: float) -> IntArray:
    """Cluster ids 1, 2, … of frames sorted in time, a new one after every gap larger than β."""
    f = np.asarray(frames, dtype=np.float64)
    ids = np.ones(f.size, dtype=np.int64)
    ids[1:] += np.cumsum(np.diff(f) > beta)
    return ids


def _points(candidates: KeyPoses, signature: FloatArray) -> FloatArray:
    return np.column_stack([candidates.frames.astype(np.float64), signature[candidates.frames]])


def kmeans_clusters(points: FloatArray, n_clusters: int, seed: int) -> IntArray:
    """k-means labels (n,) of the candidate points (n, 1 + k)."""
    k = max(1, min(n_clusters, points.shape[0]))
    model = KMeans(n_clusters=k, n_init=3, random_state=seed)
    return np.asarray(model.fit_predict(points), dtype=np.int64)


def em_clusters(points: FloatArray, counts: list[int], seed: int) -> IntArray:
    """EM (Gaussian mixture, diagonal covariances) labels (n,), the count chosen by BIC."""
    if points.shape[0] < 2:  # a mixture needs two points; one candidate is its own cluster
        return np.zeros(points.shape[0], dtype=np.int64)
    best: tuple[float, IntArray] | None = None
    for k in sorted({max(1, min(c, points.shape[0])) for c in counts}):
        model = GaussianMixture(k, covariance_type="diag", reg_covar=1e-3, random_state=seed)
        model.fit(points)
        bic = float(model.bic(points))
        if best is None or bic < best[0]:
            best = (bic, np.asarray(model.predict(points), dtype=np.int64))
    assert best is not None
    return best[1]


def cluster(candidates: KeyPoses, signature: FloatArray, options: RefineOptions) -> IntArray:
    """Eq 5.28: a cluster label for every candidate (n,)."""
    frames = candidates.frames
    if frames.size == 0:
        return np.zeros(0, dtype=np.int64)
    if options.clustering == "tc":
        return temporal_clusters(frames, options.beta)
    estimate = int(gap_clusters(frames, options.beta)[-1])
    if options.clustering == "gap":
        return gap_clusters(frames, options.beta)
    k = options.n_clusters or estimate
    points = _points(candidates, signature)
    if options.clustering == "kmeans":
        return kmeans_clusters(points, k, options.seed)
    span = 0 if options.n_clusters else options.em_span
    return em_clusters(points, list(range(k - span, k + span + 1)), options.seed)


def _distances(
    candidates: KeyPoses, signature: FloatArray, means: dict[int, FloatArray], types: IntArray
) -> FloatArray:
    """Euclidean distance of each candidate's signature to the tutor mean of the given type."""
    out = np.full(types.size, np.inf)
    for t in np.unique(types):
        rows = types == t
        if int(t) in means:
            out[rows] = np.linalg.norm(signature[candidates.frames[rows]] - means[int(t)], axis=1)
    return out


def _extremeness(
    candidates: KeyPoses, signature: FloatArray, means: dict[int, FloatArray]
) -> FloatArray:
    """Minus how far each candidate goes toward its type's tutor mean, away from the other types'
    means (projection on P̄_τ − mean of the other P̄): lower = more extreme. A patient whose range
    falls short of (or beyond) the tutor's still has the key pose at the extreme of that axis,
    where the member closest to the tutor's mean (μ1) may lie before or after it."""
    out = _distances(candidates, signature, means, candidates.types)
    for t in np.unique(candidates.types):
        others = [m for k, m in means.items() if k != int(t)]
        if int(t) not in means or not others:
            continue
        axis = means[int(t)] - np.mean(others, axis=0)
        rows = candidates.types == t
        out[rows] = -signature[candidates.frames[rows]] @ (axis / max(np.linalg.norm(axis), 1e-12))
    return out


def select(
    candidates: KeyPoses,
    labels: IntArray,
    signature: FloatArray,
    means: dict[int, FloatArray],
    selection: Selection,
) -> KeyPoses:
    """Eqs 5.31 (μ1) and 5.32–5.33 (μ2): one landmark per cluster, sorted by frame.

    μ1: the member closest to the tutor's mean signature of the member's own type.
    μ2: the cluster's most frequent type Ξ (ties: the smaller type), then among members of type Ξ
    the one closest to the tutor's mean of Ξ.
    "extreme" (ours): the member of the majority type that goes farthest along its type's axis.
    """
    frames, types = [], []
    if selection == "extreme":
        dist = _extremeness(candidates, signature, means)
    else:
        dist = _distances(candidates, signature, means, candidates.types)
    for label in np.unique(labels):
        members = np.flatnonzero(labels == label)
        if selection in ("mu2", "extreme"):
            values, counts = np.unique(candidates.types[members], return_counts=True)
            members = members[candidates.types[members] == values[np.argmax(counts)]]
        best = members[np.argmin(dist[members])]
        frames.append(int(candidates.frames[best]))
        types.append(int(candidates.types[best]))
    order = np.argsort(frames, kind="stable")
    return KeyPoses(
        np.asarray(frames, dtype=np.int64)[order], np.asarray(types, dtype=np.int64)[order]
    )


def refine(
    candidates: KeyPoses,
    signature: FloatArray,
    means: dict[int, FloatArray],
    options: RefineOptions = RefineOptions(),
) -> KeyPoses:
    """Eq 5.27: cluster the candidates and keep one per cluster.

    signature: (F, k) of the performance; means: the tutor's mean signature per type (eq 5.30,
    from `mean_poses` on the tutor's signature and ground-truth landmarks).
    """
    labels = cluster(candidates, signature, options)
    return select(candidates, labels, signature, means, options.selection)
