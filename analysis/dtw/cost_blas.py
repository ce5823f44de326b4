"""Euclidean local costs of many frames at once as a matrix product, exact where it matters.

For frames with many features, ``|a - b|^2 = |a|^2 + |b|^2 - 2 a.b`` turns the cost block of
query rows i0..i1-1 against reference columns a..b into one BLAS matrix product (about five times
faster than the direct difference loops at d = 66). The expansion cancels when ``|a - b|^2`` is
small next to ``|a|^2 + |b|^2``: its rounding error is at most ``(2 d + 4) u (|a|^2 + |b|^2)``
(u = 2^-53, the dot product's worst-case bound plus the two additions), so every cell where that
bound could exceed ``CELL_RTOL`` of the value is recomputed from the differences, in the same
order as the reference and from the unscaled features (``w (a - b)^2``: near-identical frames
lose no digits to the weight scaling). Identical frames therefore still cost exactly 0, and every
cell is within ``CELL_RTOL`` (relative) of ``tests/dtw_reference.py``'s cost.

BLAS runs on one thread (``single_threaded_blas``): the DTW code already runs its cost blocks on a
second thread or one slice of queries per core, and OpenBLAS's own threads then compete with them
(3-8 times slower on a busy 2-core machine).
"""

from __future__ import annotations

import contextlib
import functools
import math
import threading
from collections.abc import Iterator

import numba as nb
import numpy as np
import numpy.typing as npt
from threadpoolctl import ThreadpoolController

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

MIN_DIM = 16  # below this the direct loops are as fast and always exact
MIN_ROWS = 8  # a matrix product of fewer rows does not pay for its setup
MAX_WASTE = 3.0  # the product fills the band's bounding box: skip it for narrow bands
CELL_RTOL = 1e-11  # relative error allowed per cell before it is recomputed exactly
_UNIT_ROUNDOFF = 2.0**-53


@nb.njit(cache=True, nogil=True)
def recheck_factor(d: int) -> float:
    """Cells with ``|a - b|^2 < factor (|a|^2 + |b|^2)`` are recomputed from the differences."""
    return (2 * d + 4) * _UNIT_ROUNDOFF / CELL_RTOL


def worth_it(d: int, lo: IntArray, hi: IntArray) -> bool:
    """True when a matrix product over the bounding box of rows lo..hi beats the direct loops."""
    if d < MIN_DIM or lo.size < MIN_ROWS:
        return False
    needed = int(np.maximum(hi - lo + 1, 0).sum())
    box = lo.size * (int(hi.max()) - int(lo.min()) + 1)
    return needed > 0 and box <= MAX_WASTE * needed


@nb.njit(cache=True, nogil=True)
def _exact_row(  # noqa: PLR0917 - numba functions take positional arguments only
    xr: FloatArray, y: FloatArray, w: FloatArray, s: FloatArray, factor: float, orow: FloatArray
) -> None:
    """Recompute, as sum_k w_k (x_k - y_k)^2, the cells of one row where the expansion may have
    cancelled (rarely any)."""
    for t in range(s.size):
        if orow[t] < factor * s[t]:
            yr, v = y[t], 0.0
            for k in range(xr.size):
                q = xr[k] - yr[k]
                v += (w[k] if w.size else 1.0) * (q * q)
            orow[t] = v


@nb.njit(cache=True, nogil=True)
def finish(  # noqa: PLR0917
    G: FloatArray, xs: FloatArray, x: FloatArray, y: FloatArray, ynorm: FloatArray,
    w: FloatArray, a: int, euc: bool, out: FloatArray,
) -> None:  # fmt: skip
    """out[r, a + t] = cost of query row r against reference frame a + t, from G = xs . ys^T.

    xs (rows, d): the query rows scaled by sqrt(w); x (rows, d) the same rows unscaled, y (m, d)
    the unscaled reference, ynorm (m,) its scaled squared norms, w (d,) feature weights or empty.
    The main loop only counts suspicious cells (branch-free, it vectorises); the exact pass runs
    for the rows that have any."""
    width = G.shape[1]
    factor = recheck_factor(x.shape[1])
    s = np.empty(width)
    for r in range(G.shape[0]):
        xr, grow, orow = xs[r], G[r], out[r, a : a + width]
        nx = 0.0
        for k in range(xr.size):
            nx += xr[k] * xr[k]
        suspicious = 0
        for t in range(width):
            s[t] = nx + ynorm[a + t]
            orow[t] = s[t] - 2.0 * grow[t]
            suspicious += 1 if orow[t] < factor * s[t] else 0
        if suspicious:
            _exact_row(x[r], y[a : a + width], w, s, factor, orow)
        if euc:
            for t in range(width):
                orow[t] = math.sqrt(orow[t])


@functools.cache
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


class _SharedBlasLimit:
    """A counted one-thread BLAS limit: the first caller in sets it, the last one out restores
    the original, so concurrent or nested callers never undo it under each other's feet."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.users = 0
        self.limiter: contextlib.AbstractContextManager[object] | None = None

    def enter(self) -> None:
        with self.lock:
            if self.users == 0:
                self.limiter = _controller().limit(limits=1, user_api="blas")
            self.users += 1

    def leave(self) -> None:
        with self.lock:
            self.users -= 1
            if self.users == 0 and self.limiter is not None:
                self.limiter.__exit__(None, None, None)
                self.limiter = None


_SHARED_LIMIT = _SharedBlasLimit()


@contextlib.contextmanager
def single_threaded_blas(active: bool = True) -> Iterator[None]:
    """Limit BLAS to one thread while any caller is inside (process-wide, counted)."""
    if not active:
        yield
        return
    _SHARED_LIMIT.enter()
    try:
        yield
    finally:
        _SHARED_LIMIT.leave()
