"""Exact pruned DTW distance for many queries against one reference (Euclidean costs).

For a closed symmetric alignment without a path, a cell whose accumulated cost exceeds an upper
bound ``ub`` of the answer can lie on no optimal path, so neither it nor the cells reached only
through it need their local costs (the idea of Silva and Batista's PrunedDTW). ``ub`` is the cost
of one admissible path, the corner-to-corner diagonal, summed in path order: floating-point
addition is monotone, so the DP's answer is never above it and every cell of the optimal path
stays at or below it.

Each row is computed only from the first to the last column of the previous row that is at or
below ``ub`` (plus the cells reached by horizontal steps while they stay at or below it). Stored
values are never below the true accumulated cost, and a stored value at or below ``ub`` equals
it: the answer is the one the full DP gives with the same local costs. Local costs are evaluated
per cell from the differences (``w (a - b)^2``, summed in vector partial sums: within a few units
in the last place of the reference's sum), so nothing is computed for the pruned cells; for
repetitions of one exercise compared with the tutor's the live cells are a narrow band around
the diagonal (about one cell in eight for 90-frame repetitions).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.dtw.frame_costs import MODE_EUC, CostInputs
from analysis.dtw.row_blocks import concurrently, cuts

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
INF = np.inf
_MARGIN = 1e-9  # relative slack on the bound: pruning stays exact even if a cost differed by ulps


@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _four(  # noqa: PLR0917 - numba functions take positional arguments only
    x: FloatArray, y: FloatArray, w: FloatArray, i: int, j: int, out: FloatArray
) -> None:
    """out[j..j+3] = sum_k w_k (x_ik - y_jk)^2 for reference frames j..j+3: each query value is
    loaded once for four frames. The sums may be reassociated (they then run in vector partial
    sums, several times faster than one running sum); the rounding stays within a few units in
    the last place. w: feature weights (d,), ones when unweighted (``1 q q`` is ``q q``)."""
    v0, v1, v2, v3 = 0.0, 0.0, 0.0, 0.0
    for k in range(x.shape[1]):
        a, wk = x[i, k], w[k]
        q0, q1, q2, q3 = a - y[j, k], a - y[j + 1, k], a - y[j + 2, k], a - y[j + 3, k]
        v0 += wk * (q0 * q0)
        v1 += wk * (q1 * q1)
        v2 += wk * (q2 * q2)
        v3 += wk * (q3 * q3)
    out[j], out[j + 1], out[j + 2], out[j + 3] = v0, v1, v2, v3


@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _one(x: FloatArray, y: FloatArray, w: FloatArray, i: int, j: int) -> float:
    v = 0.0
    for k in range(x.shape[1]):
        q = x[i, k] - y[j, k]
        v += w[k] * (q * q)
    return v


@nb.njit(cache=True, nogil=True)
def _cell(  # noqa: PLR0917
    x: FloatArray, y: FloatArray, w: FloatArray, i: int, j: int, euc: bool
) -> float:
    """Local cost of query frame i against reference frame j (the root for the Euclidean cost)."""
    v = _one(x, y, w, i, j)
    return math.sqrt(v) if euc else v


@nb.njit(cache=True, nogil=True)
def _costs(  # noqa: PLR0917
    x: FloatArray, y: FloatArray, w: FloatArray, i: int, s: int, e: int, euc: bool,
    out: FloatArray,
) -> None:  # fmt: skip
    """Local costs of query frame i against reference frames s..e into out[s : e + 1]."""
    j = s
    while j + 4 <= e + 1:
        _four(x, y, w, i, j, out)
        j += 4
    for t in range(j, e + 1):
        out[t] = _one(x, y, w, i, t)
    if euc:
        for t in range(s, e + 1):
            out[t] = math.sqrt(out[t])


@nb.njit(cache=True, nogil=True)
def diagonal_bound(  # noqa: PLR0917
    x: FloatArray, y: FloatArray, w: FloatArray, euc: bool, lo: IntArray, hi: IntArray
) -> float:
    """Cost of the corner-to-corner path (i, j) = (k (n-1) // (L-1), k (m-1) // (L-1)),
    L = max(n, m), summed in path order; +inf when it leaves the band (then nothing is pruned)."""
    n, m = x.shape[0], y.shape[0]
    steps = max(n, m)
    total = 0.0
    for k in range(steps):
        i = k * (n - 1) // (steps - 1) if steps > 1 else 0
        j = k * (m - 1) // (steps - 1) if steps > 1 else 0
        if j < lo[i] or j > hi[i]:
            return INF
        total = total + _cell(x, y, w, i, j, euc)
    return total + total * _MARGIN


@nb.njit(cache=True, nogil=True)
def _live_range(cur: FloatArray, s: int, e: int, ub: float) -> tuple[int, int]:
    """First and last column of cur[s..e] at or below ub (e < s when none is)."""
    a, b = s, e
    while a <= e and not cur[a] <= ub:
        a += 1
    while b >= a and not cur[b] <= ub:
        b -= 1
    return a, b


@nb.njit(cache=True, nogil=True)
def distance(  # noqa: PLR0917
    x: FloatArray, y: FloatArray, w: FloatArray, euc: bool, lo: IntArray, hi: IntArray,
    prev: FloatArray, cur: FloatArray, crow: FloatArray,
) -> float:  # fmt: skip
    """Closed symmetric DTW cost of x (n, d) against y (m, d) in the band lo..hi, pruned by the
    diagonal bound; +inf when no admissible path exists. prev, cur, crow: (m,) scratch."""
    n, m = x.shape[0], y.shape[0]
    ub = diagonal_bound(x, y, w, euc, lo, hi)
    if lo[0] > 0:
        return INF
    ps, pe = 0, -1  # live columns of the previous row (none before the first)
    for i in range(n):
        s = max(ps, lo[i]) if i > 0 else 0
        e = min(pe + 1, hi[i]) if i > 0 else 0  # the cells a live upper neighbour can reach
        if s > e:
            return INF
        _costs(x, y, w, i, s, e, euc, crow)
        left = INF
        for j in range(s, e + 1):
            best = left
            if i == 0:
                best = 0.0
            else:
                if j - 1 >= ps and prev[j - 1] < best:
                    best = prev[j - 1]
                if j <= pe and prev[j] < best:
                    best = prev[j]
            left = crow[j] + best
            cur[j] = left
        j = e + 1
        while j <= hi[i] and left <= ub:  # horizontal steps past the previous row's live end
            left = _cell(x, y, w, i, j, euc) + left
            cur[j] = left
            e = j
            j += 1
        ps, pe = _live_range(cur, s, e, ub)
        if pe < ps:
            return INF
        prev, cur = cur, prev
    return prev[m - 1] if ps <= m - 1 <= pe else INF


@nb.njit(cache=True, nogil=True)
def batch(  # noqa: PLR0917
    x: FloatArray, offsets: IntArray, y: FloatArray, w: FloatArray, euc: bool,
    lo_all: IntArray, hi_all: IntArray, costs: FloatArray, b0: int, b1: int,
) -> None:  # fmt: skip
    """``distance`` for queries b0..b1-1; query b is x[offsets[b]:offsets[b+1]]."""
    m = y.shape[0]
    prev, cur, crow = np.empty(m), np.empty(m), np.empty(m)
    w = w if w.size else np.ones(x.shape[1])  # w (q q) is q q exactly for w = 1
    for b in range(b0, b1):
        s, e = offsets[b], offsets[b + 1]
        costs[b] = distance(x[s:e], y, w, euc, lo_all[s:e], hi_all[s:e], prev, cur, crow)


# The pruned batch computes a fraction of the cells; its work estimate assumes about this share
# of them (repetitions against a tutor keep a band of a few frames around the diagonal).
PRUNED_SHARE = 4


def batch_distances(
    ci: CostInputs,
    offsets: npt.NDArray[np.int64],
    lo: npt.NDArray[np.int64],
    hi: npt.NDArray[np.int64],
    costs: npt.NDArray[np.float64],
) -> None:
    """Pruned distances of every query into ``costs``, one contiguous slice of queries per
    worker thread."""
    B, m = len(offsets) - 1, ci.y.shape[0]
    euc = ci.mode == MODE_EUC
    work = int(offsets[-1]) * m * (1 + ci.x.shape[1] // 16) // PRUNED_SHARE
    slices = cuts(B, work)
    if len(slices) == 1:  # small batches (the usual case): this thread, no hand-over
        batch(ci.x, offsets, ci.y, ci.wj, euc, lo, hi, costs, 0, B)
        return
    calls: list[Callable[[], object]] = [
        functools.partial(batch, ci.x, offsets, ci.y, ci.wj, euc, lo, hi, costs, a, b)
        for a, b in slices
    ]
    concurrently(calls)
