"""Closed, unbanded symmetric DTW swept along anti-diagonals (few features per frame).

The cells (i, k - i) of anti-diagonal k do not depend on each other, so the inner loops run
over contiguous memory and vectorise, where a row sweep is one long chain of dependent minima.
The inputs are x^T (d, n) flattened and y reversed then transposed (d, m) flattened: cell
(i, k - i) then reads ``xf[f n + i]`` and ``yf[f m + (m - 1 - k) + i]``, both contiguous in i.

Buffers of accumulated costs are indexed by i + 1 (index 0 is a permanent +inf pad) and the cell
just past each diagonal is reset to +inf, so no older diagonal is ever read. Every cell is the
same floating-point sum as in ``analysis.dtw.kernels``' row sweep (local cost ``0 + sum_f q_f^2``
in feature order, then ``c + min``), and the back-pointers use the same candidate order and
strict comparisons (diagonal, vertical, horizontal), so costs and paths are identical.

With a path, the back-pointer bytes of diagonal k are stored contiguously from ``offs[k]``
(n m bytes in all, like the row layout).
"""

from __future__ import annotations

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.dtw.frame_costs import MODE_EUC

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
ByteArray = npt.NDArray[np.uint8]

DIAG, UP, LEFT, START = 0, 1, 2, 3
INF = np.inf


@nb.njit(cache=True, nogil=True)
def _diag_costs(  # noqa: PLR0917 - numba functions take positional arguments only
    mode: int, xf: FloatArray, yf: FloatArray, n: int, m: int, ilo: int, off: int,
    tmp: FloatArray, cnt: int,
) -> None:  # fmt: skip
    """Local costs of cnt cells of one anti-diagonal into tmp[0:cnt], one feature at a time."""
    d = xf.size // n
    xr, yr = xf[ilo:], yf[off + ilo :]
    if d == 1:  # one pass instead of zero, accumulate (0 + q^2 == q^2 exactly)
        for t in range(cnt):
            q = xr[t] - yr[t]
            tmp[t] = q * q
    else:
        for t in range(cnt):
            tmp[t] = 0.0
        for k in range(d):
            xr, yr = xf[k * n + ilo :], yf[k * m + off + ilo :]
            for t in range(cnt):
                q = xr[t] - yr[t]
                tmp[t] += q * q
    if mode == MODE_EUC:
        for t in range(cnt):
            tmp[t] = np.sqrt(tmp[t])


@nb.njit(cache=True, nogil=True)
def _diag_step(  # noqa: PLR0917
    tmp: FloatArray, diag: FloatArray, up: FloatArray, left: FloatArray, cur: FloatArray, cnt: int
) -> None:
    for t in range(cnt):
        v, u, w = diag[t], up[t], left[t]
        v = u if u < v else v
        v = w if w < v else v
        cur[t] = tmp[t] + v


@nb.njit(cache=True, nogil=True)
def _diag_step_dirs(  # noqa: PLR0917
    tmp: FloatArray, diag: FloatArray, up: FloatArray, left: FloatArray, cur: FloatArray,
    codes: ByteArray, cnt: int,
) -> None:  # fmt: skip
    """``_diag_step`` that also writes each cell's back-pointer (selects: they vectorise)."""
    for t in range(cnt):
        v, u, w = diag[t], up[t], left[t]
        code = UP if u < v else DIAG
        v = u if u < v else v
        code = LEFT if w < v else code
        v = w if w < v else v
        cur[t] = tmp[t] + v
        codes[t] = code


@nb.njit(cache=True, nogil=True)
def _diag_step_1d(  # noqa: PLR0917
    euc: bool, xr: FloatArray, yr: FloatArray, diag: FloatArray, up: FloatArray, left: FloatArray,
    cur: FloatArray, codes: ByteArray, want_dirs: bool, cnt: int,
) -> None:  # fmt: skip
    """One feature: local costs fused into the step (no temporary row to store and reload)."""
    for t in range(cnt):
        q = xr[t] - yr[t]
        c = np.sqrt(q * q) if euc else q * q
        v, u, w = diag[t], up[t], left[t]
        code = UP if u < v else DIAG
        v = u if u < v else v
        code = LEFT if w < v else code
        v = w if w < v else v
        cur[t] = c + v
        if want_dirs:
            codes[t] = code


@nb.njit(cache=True, nogil=True)
def _sweep(  # noqa: PLR0917
    mode: int, xf: FloatArray, yf: FloatArray, n: int, m: int, dirs: ByteArray,
    offs: IntArray, want_dirs: bool,
) -> float:  # fmt: skip
    """The sweep itself; fills dirs / offs when want_dirs. Returns D(n - 1, m - 1)."""
    p2, p1, cur = np.full(n + 1, INF), np.full(n + 1, INF), np.full(n + 1, INF)
    tmp = np.empty(n)
    at, d = 0, xf.size // n
    for k in range(n + m - 1):
        ilo, ihi = max(0, k - m + 1), min(k, n - 1)
        cnt = ihi - ilo + 1
        if want_dirs:
            offs[k] = at
        if k > 0 and d == 1:
            _diag_step_1d(mode == MODE_EUC, xf[ilo:], yf[m - 1 - k + ilo :], p2[ilo:], p1[ilo:],
                          p1[ilo + 1 :], cur[ilo + 1 :], dirs[at:], want_dirs, cnt)  # fmt: skip
            at += cnt
            if ihi + 2 <= n:
                cur[ihi + 2] = INF
            p2, p1, cur = p1, cur, p2
            continue
        _diag_costs(mode, xf, yf, n, m, ilo, m - 1 - k, tmp, cnt)
        if k == 0:
            cur[1] = tmp[0]
            if want_dirs:
                dirs[0] = START
        elif want_dirs:
            _diag_step_dirs(tmp, p2[ilo:], p1[ilo:], p1[ilo + 1 :], cur[ilo + 1 :],
                            dirs[at:], cnt)  # fmt: skip
        else:
            _diag_step(tmp, p2[ilo:], p1[ilo:], p1[ilo + 1 :], cur[ilo + 1 :], cnt)
        at += cnt
        if ihi + 2 <= n:
            cur[ihi + 2] = INF
        p2, p1, cur = p1, cur, p2
    return p1[n]


@nb.njit(cache=True, nogil=True)
def antidiagonal_cost(mode: int, xf: FloatArray, yf: FloatArray, n: int, m: int) -> float:
    """Closed-end symmetric DTW cost D(n - 1, m - 1), two diagonals of memory."""
    dummy = np.empty(1, np.uint8)
    return _sweep(mode, xf, yf, n, m, dummy, np.empty(1, np.int64), False)


@nb.njit(cache=True, nogil=True)
def antidiagonal_path(
    mode: int, xf: FloatArray, yf: FloatArray, n: int, m: int
) -> tuple[float, IntArray]:
    """Cost D(n - 1, m - 1) and the optimal path (K, 2) from (0, 0), back-pointers per diagonal."""
    dirs, offs = np.empty(n * m, np.uint8), np.empty(n + m - 1, np.int64)
    cost = _sweep(mode, xf, yf, n, m, dirs, offs, True)
    out = np.empty((n + m - 1, 2), np.int64)
    i, j, k = n - 1, m - 1, 0
    while True:
        out[k, 0], out[k, 1] = i, j
        k += 1
        code = dirs[offs[i + j] + i - max(0, i + j - m + 1)]
        if code > LEFT:
            break
        i -= 1 if code != LEFT else 0
        j -= 1 if code != UP else 0
    return cost, out[:k][::-1].copy()
