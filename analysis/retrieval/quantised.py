"""Fast motion retrieval with 2-bit quantised PCA features (paper 002, Takahara et al.).

Every frame's 17 body-part distances (`analysis.retrieval.features`) are projected on the first n
principal components of a training collection; each coefficient a_i becomes a 2-bit level g_i by
its training mean μ_i and standard deviation σ_i (eq 1), and the n levels are packed into one
integer code m = Σ g_i·4^(i−1) in [0, 4^n) (eq 2). Two codes are compared by

    dist(m_j, m_k) = Σ_i c_i · w(|g_ji − g_ki|),   w(0..3) = 0, 1, 4, 16        (eqs 3–4)

with c_i the share of variance PC i explains. All 4^n × 4^n distances are tabulated once (eq 5), so
DTW between two recordings reads every frame distance from the table instead of computing it:

    D(i, j) = d(i, j) + min(D(i−1, j−1), D(i−1, j), D(i, j−1)),   D(−1, −1) = 0

Recordings are identified by their nearest neighbour in the collection (section 4). The baseline,
`metric="features"`, runs the same DP on Euclidean distances between the continuous 17-D features.

Deviations from the paper: equality at a quantisation boundary is undefined in eq 1; here a boundary
value goes to the level above. The paper compares summed DTW costs; by default we divide them by
n + m (`normalise`), which tolerates recordings of different lengths (both metrics alike).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal, Self

import numba
import numpy as np

from analysis.retrieval.features import recording_features

LEVEL_WEIGHTS = np.array([0.0, 1.0, 4.0, 16.0])  # eq 4: cost of a level difference of 0, 1, 2, 3
Metric = Literal["lut", "features"]


@dataclass(frozen=True)
class RetrievalOptions:
    """Settings of the retrieval family (paper 002).

    n_components: PCs kept (the paper chose 6, section 4.1; the table has 4^n × 4^n entries).
    metric: "lut" (quantised codes + lookup table) or "features" (plain DTW, Euclidean on 17-D).
    normalise: divide a DTW cost by n + m so that long and short recordings compete fairly.
    frame_rate: frames per second the feature sequences are resampled to before retrieval.
    """

    n_components: int = 6
    metric: Metric = "lut"
    normalise: bool = True
    frame_rate: float | None = 15.0


# ----------------------------------------------------------------------------- codes (eqs 1–2)


def quantise(coefs: np.ndarray, mean: np.ndarray, std: np.ndarray) -> np.ndarray:
    """Eq 1: (F, n) PC coefficients → (F, n) uint8 levels 0..3 by μ − σ, μ, μ + σ per column."""
    coefs = np.asarray(coefs, dtype=np.float64)
    levels = (
        (coefs >= mean - std).astype(np.uint8)
        + (coefs >= mean).astype(np.uint8)
        + (coefs >= mean + std).astype(np.uint8)
    )
    return levels


def pack(levels: np.ndarray) -> np.ndarray:
    """Eq 2: (F, n) levels 0..3 → (F,) int64 codes Σ g_i·4^(i−1), first PC = lowest digit."""
    levels = np.asarray(levels, dtype=np.int64)
    return levels @ (4 ** np.arange(levels.shape[1], dtype=np.int64))


def unpack(codes: np.ndarray, n_components: int) -> np.ndarray:
    """Inverse of `pack`: (F,) codes → (F, n) uint8 levels."""
    codes = np.asarray(codes, dtype=np.int64)
    shifts = 2 * np.arange(n_components, dtype=np.int64)
    return ((codes[:, None] >> shifts) & 3).astype(np.uint8)


def code_distance(a: int, b: int, weights: np.ndarray) -> float:
    """Eqs 3–4 for one pair of codes (readable reference of `lookup_table`); weights: (n,) c_i."""
    levels = unpack(np.array([a, b]), len(weights)).astype(np.int64)
    return float(np.sum(weights * LEVEL_WEIGHTS[np.abs(levels[0] - levels[1])]))


def lookup_table(weights: np.ndarray, dtype: type = np.float32) -> np.ndarray:
    """Eq 5: the (4^n, 4^n) table of `code_distance` for every pair of codes; weights: (n,) c_i.

    Built digit by digit: with code = g_k·4^(k−1) + rest,
    T_k[(g, r), (h, s)] = c_k·w(|g − h|) + T_{k−1}[r, s].
    """
    table = np.zeros((1, 1), dtype=np.float64)
    g = np.arange(4)
    for c in np.asarray(weights, dtype=np.float64):
        digit = c * LEVEL_WEIGHTS[np.abs(g[:, None] - g[None, :])]
        size = table.shape[0]
        table = (digit[:, None, :, None] + table[None, :, None, :]).reshape(4 * size, 4 * size)
    return table.astype(dtype)


# ----------------------------------------------------------------------------- DTW kernels


@numba.njit(cache=True)
def _dp_step(prev: np.ndarray, cur: np.ndarray, cost: np.ndarray, rows: int) -> None:
    """Advance the DP by `rows` (1 or 2) rows; prev/cur: (m + 1,) rows with the border at index 0.

    Reads the row above from prev and writes the last new row to cur. Two rows are interleaved, the
    second lagging one column, so the CPU works on two independent min-plus chains at once: about
    1.7× faster than one row at a time, for both frame-distance sources alike.
    """
    m = cost.shape[1]
    if rows == 1:
        left = np.inf
        for j in range(m):
            left = cost[0, j] + min(prev[j], prev[j + 1], left)
            cur[j + 1] = left
    else:
        a_left = cost[0, 0] + min(prev[0], prev[1])  # D(i, j-1)
        a_diag = np.inf  # D(i, j-2)
        b_left = np.inf  # D(i+1, j-2)
        for j in range(1, m):
            b = cost[1, j - 1] + min(a_diag, a_left, b_left)
            a = cost[0, j] + min(prev[j], prev[j + 1], a_left)
            cur[j] = b
            a_diag, a_left, b_left = a_left, a, b
        cur[m] = cost[1, m - 1] + min(a_diag, a_left, b_left)
    cur[0] = np.inf


@numba.njit(cache=True)
def _fill_lut(code: int, b: np.ndarray, lut: np.ndarray, out: np.ndarray) -> None:
    """Frame distances of one query frame to every frame of b, read from the table."""
    row = lut[code]
    for j in range(b.shape[0]):
        out[j] = row[b[j]]


@numba.njit(cache=True, fastmath=True)
def _fill_euclidean(frame: np.ndarray, bt: np.ndarray, out: np.ndarray) -> None:
    """Euclidean distances of one query frame (d,) to every frame of b given as bt (d, m).

    Dimension-outer loops let the compiler vectorise across frames: a fair, fast baseline.
    """
    out[:] = 0.0
    for k in range(bt.shape[0]):
        value = frame[k]
        for j in range(bt.shape[1]):
            diff = value - bt[k, j]
            out[j] += diff * diff
    for j in range(bt.shape[1]):
        out[j] = np.sqrt(out[j])


@numba.njit(cache=True)
def _dp_start(m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """prev (row −1: D(−1, −1) = 0, else ∞), cur, and a (2, m) cost buffer."""
    prev = np.full(m + 1, np.inf)
    prev[0] = 0.0
    return prev, np.full(m + 1, np.inf), np.empty((2, m))


@numba.njit(cache=True)
def dtw_lut(a: np.ndarray, b: np.ndarray, lut: np.ndarray) -> float:
    """DTW cost between code sequences a (n,) and b (m,), frame distances read from `lut`."""
    if a.shape[0] == 0 or b.shape[0] == 0:
        return np.inf  # no warping path joins an empty sequence
    prev, cur, cost = _dp_start(b.shape[0])
    i = 0
    while i < a.shape[0]:
        rows = min(2, a.shape[0] - i)
        for r in range(rows):
            _fill_lut(a[i + r], b, lut, cost[r])
        _dp_step(prev, cur, cost, rows)
        prev, cur = cur, prev
        i += rows
    return float(prev[b.shape[0]])


@numba.njit(cache=True)
def dtw_features(a: np.ndarray, bt: np.ndarray) -> float:
    """DTW cost between a (n, d) and b given transposed as bt (d, m), Euclidean frame distances."""
    if a.shape[0] == 0 or bt.shape[1] == 0:
        return np.inf  # no warping path joins an empty sequence
    prev, cur, cost = _dp_start(bt.shape[1])
    i = 0
    while i < a.shape[0]:
        rows = min(2, a.shape[0] - i)
        for r in range(rows):
            _fill_euclidean(a[i + r], bt, cost[r])
        _dp_step(prev, cur, cost, rows)
        prev, cur = cur, prev
        i += rows
    return float(prev[bt.shape[1]])


@numba.njit(cache=True)
def _many_lut(
    query: np.ndarray, codes: np.ndarray, offsets: np.ndarray, lut: np.ndarray
) -> np.ndarray:
    out = np.empty(offsets.shape[0] - 1)
    for r in range(out.shape[0]):
        out[r] = dtw_lut(query, codes[offsets[r] : offsets[r + 1]], lut)
    return out


@numba.njit(cache=True)
def _many_features(query: np.ndarray, feats_t: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    out = np.empty(offsets.shape[0] - 1)
    for r in range(out.shape[0]):
        out[r] = dtw_features(query, np.ascontiguousarray(feats_t[:, offsets[r] : offsets[r + 1]]))
    return out


# ----------------------------------------------------------------------------- estimator


class MotionRetriever:
    """Nearest-neighbour motion retrieval over a labelled collection of recordings (paper 002).

    Recordings are (F, 17) feature sequences from `analysis.retrieval.features.recording_features`
    at `frame_rate` frames per second (`features_from_positions` does that from positions).
    Learned attributes are plain numpy arrays, so the estimator pickles; the 4^n × 4^n table is
    rebuilt on first use instead of being stored (64 MB for n = 6).
    """

    def __init__(
        self,
        *,
        n_components: int = 6,
        metric: Metric = "lut",
        normalise: bool = True,
        frame_rate: float | None = 15.0,
    ) -> None:
        self.n_components = n_components
        self.metric = metric
        self.normalise = normalise
        self.frame_rate = frame_rate
        self._lut: np.ndarray | None = None

    @property
    def options(self) -> RetrievalOptions:
        return RetrievalOptions(self.n_components, self.metric, self.normalise, self.frame_rate)

    def fit(self, recordings: Sequence[np.ndarray], labels: Sequence[Any]) -> Self:
        """PCA over all frames of `recordings` (each (F, 17)), thresholds, and every code."""
        if len(recordings) != len(labels) or not recordings:
            raise ValueError("fit needs as many labels as recordings, and at least one recording")
        if self.metric not in ("lut", "features"):
            raise ValueError(f"unknown metric {self.metric!r}")
        frames = np.concatenate([np.asarray(r, dtype=np.float64) for r in recordings])
        if not 1 <= self.n_components <= min(frames.shape):
            raise ValueError(f"n_components must be in 1..{min(frames.shape)}")
        self.mean_ = frames.mean(axis=0)
        variances, vectors = np.linalg.eigh(np.cov(frames - self.mean_, rowvar=False))
        order = np.argsort(variances)[::-1][: self.n_components]
        self.components_ = vectors[:, order].T  # (n, 17)
        self.explained_variance_ratio_ = np.clip(variances[order], 0.0, None) / variances.sum()
        coefs = (frames - self.mean_) @ self.components_.T
        self.coef_mean_ = coefs.mean(axis=0)
        self.coef_std_ = coefs.std(axis=0)
        self.offsets_ = np.concatenate([[0], np.cumsum([len(r) for r in recordings])]).astype(
            np.int64
        )
        self.codes_ = self.codes(frames)
        # (17, total) frames, kept only for the baseline metric: a LUT retriever pickles small.
        self.features_t_ = np.ascontiguousarray(
            frames.T if self.metric == "features" else frames.T[:, :0]
        )
        self.labels_ = np.asarray(labels)
        self._lut = None
        return self

    @property
    def lut_(self) -> np.ndarray:
        """The (4^n, 4^n) float32 table of eq 5 for the fitted c_i."""
        if self._lut is None:
            self._lut = lookup_table(self.explained_variance_ratio_)
        return self._lut

    def codes(self, features: np.ndarray) -> np.ndarray:
        """(F, 17) features → (F,) int64 frame codes in [0, 4^n) (eqs 1–2)."""
        coefs = (np.asarray(features, dtype=np.float64) - self.mean_) @ self.components_.T
        return pack(quantise(coefs, self.coef_mean_, self.coef_std_))

    def distances(self, recording: np.ndarray) -> np.ndarray:
        """(N,) DTW cost from `recording` (F, 17) to every recording of the collection."""
        recording = np.asarray(recording, dtype=np.float64)
        if self.metric == "lut":
            costs = _many_lut(self.codes(recording), self.codes_, self.offsets_, self.lut_)
        else:
            costs = _many_features(recording, self.features_t_, self.offsets_)
        if self.normalise:
            costs = costs / (len(recording) + np.diff(self.offsets_))
        return costs

    def most_similar(self, recording: np.ndarray, k: int = 5) -> list[tuple[int, float]]:
        """The k nearest recordings of the collection as (index, distance), nearest first."""
        costs = self.distances(recording)
        order = np.argsort(costs, kind="stable")[:k]
        return [(int(i), float(costs[i])) for i in order]

    def identify(self, recording: np.ndarray) -> Any:
        """The label of the nearest recording (1-NN, as in the paper)."""
        index, _ = self.most_similar(recording, k=1)[0]
        return self.labels_[index].item()

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_lut"] = None  # rebuilt on demand: cheaper than 64 MB in every pickle
        return state


def features_from_positions(
    retriever: MotionRetriever, positions: np.ndarray, names: Sequence[str], fps: float
) -> np.ndarray:
    """(F, J, 3) world positions + joint names → (F', 17) features at the retriever's frame rate."""
    return recording_features(positions, names, fps, target_fps=retriever.frame_rate)


def frame_codes(
    retriever: MotionRetriever, positions: np.ndarray, names: Sequence[str], fps: float
) -> np.ndarray:
    """(F, J, 3) world positions + joint names → (F',) int64 frame codes of a fitted retriever."""
    return retriever.codes(features_from_positions(retriever, positions, names, fps))
