r"""Dynamic time warping: one ``align(x, y, options)`` for offline, subsequence and Type V DTW.

x (n, d) is the query (rows i), y (m, d) the reference (columns j); ``c(i, j)`` is the local cost
of ``DTWOptions.cost`` (see ``analysis.dtw.frame_costs``), per-joint weights included.

Symmetric steps (default)::

    D(i, j) = c(i, j) + min{ D(i-1, j-1), D(i-1, j), D(i, j-1), S(i, j) }

where ``S(i, j) = 0`` for a start cell and ``inf`` otherwise: the start cell is (0, 0), or any
(0, j) with ``open_begin`` (subsequence DTW). Cells outside the Sakoe-Chiba band are ``inf``; the
band is ``|j (n-1) - i (m-1)| <= window (n-1)`` around the corner-to-corner diagonal, or
``|j - i| <= window`` when an end is open (the diagonal is then unknown). Ties go to the first
candidate in the order written (diagonal, vertical, horizontal, start).

Path-length weighting (paper 000, eq 3) keeps the path length L and picks the predecessor p by the
mean cost the path would have, then accumulates plain sums::

    p* = argmin_p (D(p) + c(i, j)) / (L(p) + 1),   D(i, j) = c(i, j) + D(p*),   L(i, j) = L(p*) + 1

with ``D = L = 0`` for the virtual start predecessor.

Type V (``step="type-v"``, paper 003 ch. 6, Table 6.3) maps every query frame to exactly one
reference frame; the reference advances 0-3 frames per query frame and may stand still at most twice
in a row. With constraint states s = 0 (free), 1, 2 (number of repeats so far)::

    D0(i, j) = c(i, j) + min{ D0(i-1, j-1), D1(i-1, j-1), D2(i-1, j-1),
                              D0(i-1, j-2), D0(i-1, j-3), S(i, j) }
    D1(i, j) = c(i, j) + D0(i-1, j)
    D2(i, j) = c(i, j) + D1(i-1, j)
    D(i, j)  = min_s Ds(i, j)

(every Type V path has length i + 1, so path-length weighting changes nothing there).

The path ends at (n-1, m-1), or with ``open_end`` at ``(n-1, Omega)`` with
``Omega = argmin_j D(n-1, j)`` (``D / L`` with path-length weighting, where paths of different
lengths compete): the Open-End DTW of Tormene et al. used in paper 000. ``Alignment.cost`` is
``D`` at the end cell, i.e. the sum of the local costs along the path; with ``speed_insensitive``
it is re-scored by paper 001 eq 17: a run of frames of one sequence matched to a single frame of
the other counts once, with their mean frame.

Fast paths (numba, in ``analysis.dtw.kernels``) are chosen automatically: local costs computed in
cache-sized row blocks on a second thread while the DP consumes the previous block (Euclidean
costs with 16 or more features as one matrix product per block, ``analysis.dtw.cost_blas``),
a vectorised anti-diagonal sweep for closed unbanded alignments with few features (with or
without the path, ``analysis.dtw.diagonal_kernels``), two rows of
memory when no path is wanted (with a path and a closed begin, ``kernels.rows_path``: the
general row without its range tests), and a batched kernel for many queries against one
reference (``align_batch`` / ``distance_batch``), one slice of queries per core
(``analysis.dtw.row_blocks``). Closed symmetric Euclidean distances of a batch are pruned
(``analysis.dtw.pruned``): cells whose accumulated cost exceeds the corner-to-corner path's
never get local costs, with the same result.
``tests/dtw_reference.py`` is the plain version they are tested against.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import numpy.typing as npt

from analysis.dtw import cost_blas, pruned
from analysis.dtw import diagonal_kernels as diag_kern
from analysis.dtw import kernels as kern
from analysis.dtw.cost_blas import single_threaded_blas
from analysis.dtw.frame_costs import (
    MODE_EUC,
    MODE_SQ,
    CostInputs,
    CostKind,
    as_frames,
    check_kind,
    joint_weights,
    speed_insensitive_cost,
)
from analysis.dtw.row_blocks import concurrently, cuts, run_rows

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
StepKind = Literal["symmetric", "type-v"]
DIAGONAL_MAX_DIM = 8  # the anti-diagonal sweep recomputes costs per diagonal: few features only


@dataclass(frozen=True)
class DTWOptions:
    """Settings shared by every DTW variant (offline, open-end, streaming, batched).

    cost: local cost kind ("euclidean", "sqeuclidean", "quaternion", "geodesic").
    weights: per-joint weights (J,), see ``analysis.dtw.frame_costs``; None means all ones.
    window: Sakoe-Chiba half-width in frames (see the band above); None means no band.
    open_begin / open_end: the path may start / end anywhere along y (subsequence, open-end DTW).
    path_length_weighting: predecessor choice by mean path cost (paper 000, eq 3).
    step: "symmetric" (steps (1,0), (0,1), (1,1), unweighted) or "type-v" (paper 003, ch. 6).
    speed_insensitive: re-score ``cost`` with paper 001 eq 17 (the path is unchanged).
    return_matrix: also return the accumulated cost matrix D (n, m); costs n*m*8 bytes.
    """

    cost: CostKind = "euclidean"
    weights: tuple[float, ...] | None = None
    window: int | None = None
    open_begin: bool = False
    open_end: bool = False
    path_length_weighting: bool = False
    step: StepKind = "symmetric"
    speed_insensitive: bool = False
    return_matrix: bool = False

    def __post_init__(self) -> None:
        check_kind(self.cost)
        if self.step not in ("symmetric", "type-v"):
            raise ValueError(f"step must be 'symmetric' or 'type-v', got {self.step!r}")
        if self.window is not None and (int(self.window) != self.window or self.window < 0):
            raise ValueError(f"window must be a non-negative integer, got {self.window!r}")
        if self.weights is not None:
            w = tuple(float(v) for v in np.asarray(self.weights, dtype=np.float64).ravel())
            if not w or any(not np.isfinite(v) or v < 0 for v in w):
                raise ValueError("weights must be a non-empty sequence of finite values >= 0")
            object.__setattr__(self, "weights", w)


@dataclass(frozen=True, eq=False)
class Alignment:
    """Result of ``align``: cost, path (K, 2) of (i, j), accumulated matrix (n, m) if asked."""

    cost: float
    path: IntArray
    matrix: FloatArray | None = field(default=None, repr=False)

    @property
    def normalized_cost(self) -> float:
        """Cost divided by the number of path cells."""
        return self.cost / len(self.path)

    @property
    def end(self) -> int:
        """Reference frame matched to the last query frame."""
        return int(self.path[-1, 1])


def band_limits(n: int, m: int, options: DTWOptions) -> tuple[IntArray, IntArray]:
    """Admissible columns lo[i]..hi[i] per row (inclusive), exact integer arithmetic: (n,), (n,)."""
    i = np.arange(n, dtype=np.int64)
    if options.window is None or n == 1:
        return np.zeros(n, np.int64), np.full(n, m - 1, np.int64)
    w = int(options.window)
    if options.open_begin or options.open_end:
        lo, hi = i - w, i + w
    else:
        lo = -((w * (n - 1) - i * (m - 1)) // (n - 1))  # ceil((i (m-1) - w (n-1)) / (n-1))
        hi = (i * (m - 1) + w * (n - 1)) // (n - 1)
    return np.clip(lo, 0, m), np.clip(hi, -1, m - 1)  # lo > hi: the row has no admissible cell


def prepare(
    x: npt.ArrayLike, y: npt.ArrayLike, options: DTWOptions
) -> tuple[FloatArray, FloatArray, CostInputs]:
    """Validated (n, d), (m, d) float arrays and the cost inputs the kernels read."""
    xa, ya = as_frames(x, "x"), as_frames(y, "y")
    if xa.shape[1] != ya.shape[1]:
        raise ValueError(f"x has {xa.shape[1]} features per frame, y has {ya.shape[1]}")
    joint_weights(xa.shape[1], options.cost, options.weights)  # validates the weight count
    return xa, ya, CostInputs(xa, ya, options.cost, options.weights)


class DPState:
    """Working arrays of one DP run: the last two rows (and path lengths), back-pointers
    (n, m) when a path is wanted, the full matrix on request and, with ``omega``, every row's
    open-end answer (what a streaming aligner would have said after that row)."""

    def __init__(self, n: int, m: int, options: DTWOptions, path: bool, omega: bool = False):
        self.opt = options
        self.typev = options.step == "type-v"
        self.D = np.full((2, 3, m) if self.typev else (2, m), np.inf)
        self.L = np.ones((2, m))
        self.dirs = np.empty((n, m) if path else (1, m), np.uint8)
        self.want_dirs, self.want_omega = path, omega
        self.full = np.empty((n, m) if options.return_matrix else (1, m))
        self.omega = np.empty(n if omega else 1, np.int64)
        plain = not (options.open_begin or options.path_length_weighting or options.return_matrix)
        self.cost_only = plain and not (path or omega or self.typev)
        self.path_only = plain and path and not (omega or self.typev)

    def rows(self, C: FloatArray, i0: int, i1: int, lo: IntArray, hi: IntArray) -> None:
        """Advance the DP over rows i0..i1-1 whose local costs are C[0 : i1 - i0]."""
        head = (C, i0, i1, lo, hi, bool(self.opt.open_begin))
        tail = (
            self.dirs,
            self.want_dirs,
            self.full,
            self.opt.return_matrix,
            self.omega,
            self.want_omega,
        )
        if self.typev:
            kern.rows_typev(*head, self.D, *tail)
        elif self.cost_only:
            kern.rows_cost(C, i0, i1, lo, hi, self.D)
        elif self.path_only:
            kern.rows_path(C, i0, i1, lo, hi, self.D, self.dirs)
        else:
            kern.rows_symmetric(*head, bool(self.opt.path_length_weighting), self.D, self.L, *tail)

    def backtrack(self, i: int, j: int) -> IntArray:
        """The path (K, 2) from the start to cell (i, j) of the last computed row."""
        out = np.empty((i + 1 + self.D.shape[-1], 2), np.int64)
        if self.typev:
            k = kern.backtrack_typev(self.dirs, i, j, kern.typev_end_state(self.D, i, j), out)
        else:
            k = kern.backtrack_symmetric(self.dirs, i, j, out)
        return np.ascontiguousarray(out[:k][::-1])


def _end_cell(buf: DPState, lo: IntArray, hi: IntArray) -> tuple[int, float]:
    """End column of the path (m - 1, or the open-end argmin) and the accumulated cost there."""
    n, m, opt = len(lo), buf.D.shape[-1], buf.opt
    a, b = int(lo[n - 1]), int(hi[n - 1])
    last = buf.D[(n - 1) & 1]
    row = last.min(axis=0) if buf.typev else last
    j = m - 1
    if opt.open_end:
        keys = row[a : b + 1]
        if opt.path_length_weighting and not buf.typev:
            keys = keys / buf.L[(n - 1) & 1][a : b + 1]
        j = a + int(np.argmin(keys)) if b >= a else -1
    value = float(row[j]) if a <= j <= b else np.inf
    if not np.isfinite(value):
        raise ValueError(
            f"no admissible warping path for {n} x {m} frames with these options "
            f"(window={opt.window}, step={opt.step})"
        )
    return j, value


def align(x: npt.ArrayLike, y: npt.ArrayLike, options: DTWOptions | None = None) -> Alignment:
    """Optimal warping path between x (n, d) and y (m, d) under ``options`` (see module doc)."""
    opt = options or DTWOptions()
    xa, ya, ci = prepare(x, y, opt)
    n, m = len(xa), len(ya)
    if _diagonal_sweep(opt, ci) and not opt.return_matrix:
        cost, path = diag_kern.antidiagonal_path(ci.mode, *_diagonal_inputs(ci), n, m)
        if opt.speed_insensitive:
            cost = speed_insensitive_cost(xa, ya, path, opt.cost, opt.weights)
        return _result(cost, path, None)
    lo, hi = band_limits(n, m, opt)
    buf = DPState(n, m, opt, path=True)
    run_rows(ci, lo, hi, buf)
    j, cost = _end_cell(buf, lo, hi)
    path = buf.backtrack(n - 1, j)
    if opt.speed_insensitive:
        cost = speed_insensitive_cost(xa, ya, path, opt.cost, opt.weights)
    return _result(cost, path, buf.full if opt.return_matrix else None)


def distance(x: npt.ArrayLike, y: npt.ArrayLike, options: DTWOptions | None = None) -> float:
    """``align(x, y, options).cost`` without the path: two rows of memory, no back-pointers."""
    opt = options or DTWOptions()
    if opt.speed_insensitive or opt.return_matrix:
        return align(x, y, opt).cost
    xa, ya, ci = prepare(x, y, opt)
    n, m = len(xa), len(ya)
    if _diagonal_sweep(opt, ci):
        xf, yf = _diagonal_inputs(ci)
        return float(diag_kern.antidiagonal_cost(ci.mode, xf, yf, n, m))
    lo, hi = band_limits(n, m, opt)
    buf = DPState(n, m, opt, path=False)
    run_rows(ci, lo, hi, buf)
    return _end_cell(buf, lo, hi)[1]


def _diagonal_sweep(opt: DTWOptions, ci: CostInputs) -> bool:
    """Closed, unbanded, unweighted, few features: the vectorised anti-diagonal sweep applies
    (it recomputes local costs per diagonal, cheap only for few features)."""
    closed = opt == DTWOptions(
        cost=opt.cost, speed_insensitive=opt.speed_insensitive, return_matrix=opt.return_matrix
    )
    return closed and ci.mode in (MODE_EUC, MODE_SQ) and ci.x.shape[1] <= DIAGONAL_MAX_DIM


def _diagonal_inputs(ci: CostInputs) -> tuple[FloatArray, FloatArray]:
    """x^T and reversed y^T, flattened: the layout ``analysis.dtw.diagonal_kernels`` reads."""
    return ci.x.T.ravel(), ci.yt[:, ::-1].ravel()


def _result(cost: float, path: IntArray, matrix: FloatArray | None) -> Alignment:
    path.setflags(write=False)
    if matrix is not None:
        matrix.setflags(write=False)
    return Alignment(cost=float(cost), path=path, matrix=matrix)


@dataclass(frozen=True)
class _Batch:
    frames: list[FloatArray]
    y: FloatArray
    costs: FloatArray
    paths: IntArray
    starts: IntArray
    lengths: IntArray


def _stack(xs: Sequence[npt.ArrayLike], m: int) -> tuple[list[FloatArray], IntArray]:
    """Queries as (n_b, d) float arrays (1-D becomes (n, 1)) and their row offsets (B + 1,)."""
    frames = [np.asarray(x, dtype=np.float64) for x in xs]
    frames = [f[:, None] if f.ndim == 1 else f for f in frames]
    if not frames or any(f.ndim != 2 or len(f) == 0 for f in frames):
        raise ValueError("xs must be a non-empty list of non-empty (frames, features) arrays")
    lens = np.array([len(f) for f in frames], np.int64)
    return frames, np.concatenate([[0], np.cumsum(lens)]).astype(np.int64)


def _run_batch(
    xs: Sequence[npt.ArrayLike], y: npt.ArrayLike, opt: DTWOptions, paths: bool
) -> _Batch:
    """Stack the queries and run local costs and DPs on one thread per core, each thread a
    contiguous slice of queries."""
    ya = as_frames(y, "y")
    m = len(ya)
    frames, offsets = _stack(xs, m)
    N, B = int(offsets[-1]), len(frames)
    _, _, ci = prepare(np.concatenate(frames), ya, opt)
    if opt.window is None:  # every row spans the whole reference (the common case, no copies)
        lo, hi = np.zeros(N, np.int64), np.full(N, m - 1, np.int64)
    else:
        bands = {n: band_limits(n, m, opt) for n in {len(f) for f in frames}}
        lo = np.concatenate([bands[len(f)][0] for f in frames])
        hi = np.concatenate([bands[len(f)][1] for f in frames])
    if not paths and _prunable(opt, ci):  # no path buffers: costs only
        none = np.zeros(B, np.int64)
        r = _Batch(frames, ya, np.empty(B), np.empty((1, 2), np.int64), none, none)
        pruned.batch_distances(ci, offsets, lo, hi, r.costs)
        return _checked(r)
    poffs = np.concatenate([[0], np.cumsum(np.diff(offsets) + m)]).astype(np.int64)
    r = _Batch(frames, ya, np.empty(B), np.empty((int(poffs[-1]) if paths else 1, 2), np.int64),
               poffs, np.zeros(B, np.int64))  # fmt: skip
    C = np.empty((N, m))
    flags = (bool(opt.open_begin), bool(opt.open_end), bool(opt.path_length_weighting))
    tail = (r.costs, r.paths, r.lengths)

    def work(b0: int, b1: int) -> None:
        r0, r1 = int(offsets[b0]), int(offsets[b1])
        ci.rows(r0, r1, lo, hi, C[r0:r1])
        kern.batch(C, offsets, lo, hi, *flags, opt.step == "type-v", paths, poffs, *tail, b0, b1)

    slices = cuts(B, N * m * (1 + ya.shape[1] // 16))
    with single_threaded_blas(ci.uses_blas and N >= cost_blas.MIN_ROWS):
        concurrently([functools.partial(work, a, b) for a, b in slices])
    return _checked(r)


def _checked(r: _Batch) -> _Batch:
    if not np.all(np.isfinite(r.costs)):
        bad = int(np.flatnonzero(~np.isfinite(r.costs))[0])
        raise ValueError(f"no admissible warping path for query {bad} with these options")
    return r


def _prunable(opt: DTWOptions, ci: CostInputs) -> bool:
    """Closed symmetric Euclidean distances without path-length weighting: the pruned DP of
    ``analysis.dtw.pruned`` gives the same sums while skipping the cells off the optimal path."""
    plain = not (opt.open_begin or opt.open_end or opt.path_length_weighting)
    return plain and opt.step == "symmetric" and ci.mode in (MODE_EUC, MODE_SQ)


def distance_batch(
    xs: Sequence[npt.ArrayLike], y: npt.ArrayLike, options: DTWOptions | None = None
) -> FloatArray:
    """``distance(x, y, options)`` for many queries x (n_b, d) against one y (m, d): (B,)."""
    opt = options or DTWOptions()
    if opt.speed_insensitive or opt.return_matrix:
        return np.array([a.cost for a in align_batch(xs, y, opt)])
    return _run_batch(xs, y, opt, paths=False).costs


def align_batch(
    xs: Sequence[npt.ArrayLike], y: npt.ArrayLike, options: DTWOptions | None = None
) -> list[Alignment]:
    """``align(x, y, options)`` for many queries against one reference, in parallel."""
    opt = options or DTWOptions()
    if opt.return_matrix:
        return [align(x, y, opt) for x in xs]
    r = _run_batch(xs, y, opt, paths=True)
    result = []
    for b, x in enumerate(r.frames):
        path = np.ascontiguousarray(r.paths[r.starts[b] : r.starts[b] + r.lengths[b]][::-1])
        cost = float(r.costs[b])
        if opt.speed_insensitive:
            cost = speed_insensitive_cost(x, r.y, path, opt.cost, opt.weights)
        result.append(_result(cost, path, None))
    return result
