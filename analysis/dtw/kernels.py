"""Compiled dynamic programmes behind ``analysis.dtw`` (numba, float64, no fastmath).

Every kernel implements exactly the recurrences written in ``analysis.dtw``'s docstring, with the
same candidate order and strict ``<`` comparisons as ``tests/dtw_reference.py``, so that the
accumulated costs are the same floating-point sums and the paths are the same on untied inputs.

Shared conventions:

- x is the query (rows i, n frames), y the reference (columns j, m frames); row i's local costs
  are ``C[i - i0]`` of the block being processed.
- ``lo[i]..hi[i]`` is the admissible band of row i (non-decreasing in i).
- The last two rows of the accumulated cost live in ``D2[i & 1]`` (path lengths in ``L2``; Type V
  keeps one row per constraint state in ``D3[i & 1, s]``), so a computation can be split into row
  blocks or fed one streamed frame at a time.
- Back-pointers are bytes (n, m): symmetric ``DIAG/UP/LEFT/START``; Type V state-0 cells store
  ``4 k + s'`` (came from column j - k in state s'), states 1 and 2 have implicit predecessors.
- Outputs that are not wanted are one-row scratch buffers with their ``want_*`` flag off.

Numba functions take positional arguments only, hence the long signatures (noqa: PLR0917).
"""

from __future__ import annotations

import numba as nb
import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
ByteArray = npt.NDArray[np.uint8]

DIAG, UP, LEFT, START, NONE = 0, 1, 2, 3, 255
TV_START = 15
INF = np.inf


@nb.njit(cache=True, nogil=True)
def _starts(j: int, start: int) -> bool:
    """start: 0 none in this row, 1 only (0, 0), 2 every cell (open begin, first row)."""
    return start == 2 or (start == 1 and j == 0)


@nb.njit(cache=True, nogil=True)
def _row_plain(  # noqa: PLR0917
    a: int, b: int, pa: int, pb: int, start: int, crow: FloatArray, prev: FloatArray,
    cur: FloatArray, drow: ByteArray,
) -> None:  # fmt: skip
    """One row of D(i,j) = c(i,j) + min(D(i-1,j-1), D(i-1,j), D(i,j-1), start).

    Value comparisons are written as selects: they are unpredictable, branches would stall.
    """
    left = INF  # carried in a register (a reload of cur[j - 1] would lengthen the chain)
    for j in range(a, b + 1):
        diag = prev[j - 1] if pa <= j - 1 <= pb else INF
        up = prev[j] if pa <= j <= pb else INF
        best = diag
        code = DIAG if diag < INF else NONE
        code = UP if up < best else code
        best = up if up < best else best
        code = LEFT if left < best else code
        best = left if left < best else best
        if _starts(j, start) and best > 0.0:
            code = START
            best = 0.0
        left = crow[j] + best
        cur[j] = left
        drow[j] = code


@nb.njit(cache=True, nogil=True)
def rows_cost(  # noqa: PLR0917
    C: FloatArray, i0: int, i1: int, lo: IntArray, hi: IntArray, D2: FloatArray
) -> None:
    """Cost-only closed-begin symmetric DP over rows i0..i1-1 (no back-pointers, no lengths).

    Cells just outside the previous row's band are reset to +inf before they are read, so the
    inner loop is three branch-free minima (about 4 cycles a cell on its add/min chain).
    """
    for i in range(i0, i1):
        a, b = lo[i], hi[i]
        crow, cur, prev = C[i - i0], D2[i & 1], D2[(i + 1) & 1]
        if a > b:
            continue
        if i == 0:
            cur[a] = crow[a] if a == 0 else INF
        else:
            pa, pb = lo[i - 1], hi[i - 1]
            for j in range(max(pb + 1, a), b + 1):
                prev[j] = INF
            d0 = prev[a - 1] if pa < a <= pb + 1 else INF
            cur[a] = crow[a] + min(d0, prev[a])
        w = cur[a]  # the left neighbour stays in a register: no store-to-load round trip
        for j in range(a + 1, b + 1):
            v = prev[j - 1] if i > 0 else INF
            u = prev[j] if i > 0 else INF
            v = u if u < v else v
            v = w if w < v else v
            w = crow[j] + v
            cur[j] = w


@nb.njit(cache=True, nogil=True)
def rows_path(  # noqa: PLR0917
    C: FloatArray, i0: int, i1: int, lo: IntArray, hi: IntArray, D2: FloatArray, dirs: ByteArray
) -> None:
    """``rows_symmetric`` for a closed begin without path-length weighting: the same values and
    back-pointers (same candidate order, strict ``<``), with the band handled as in
    ``rows_cost`` (previous-row cells past its band reset to +inf before they are read) so that
    the inner loop has no range tests: about half the time of the general row."""
    for i in range(i0, i1):
        a, b = lo[i], hi[i]
        crow, cur, prev, drow = C[i - i0], D2[i & 1], D2[(i + 1) & 1], dirs[i]
        if a > b:
            continue
        if i == 0:
            diag = up = INF
            drow[a] = START if a == 0 else NONE
            w = crow[a] if a == 0 else INF
        else:
            pa, pb = lo[i - 1], hi[i - 1]
            for j in range(max(pb + 1, a), b + 1):
                prev[j] = INF
            diag = prev[a - 1] if pa < a <= pb + 1 else INF
            up = prev[a]
            best = up if up < diag else diag
            drow[a] = (UP if up < diag else DIAG) if best < INF else NONE
            w = crow[a] + best
        cur[a] = w
        for j in range(a + 1, b + 1):  # the left neighbour w stays in a register
            diag = prev[j - 1] if i > 0 else INF
            up = prev[j] if i > 0 else INF
            code = DIAG if diag < INF else NONE
            code = UP if up < diag else code
            best = up if up < diag else diag
            code = LEFT if w < best else code
            best = w if w < best else best
            w = crow[j] + best
            cur[j] = w
            drow[j] = code


@nb.njit(cache=True, nogil=True)
def _row_plw(  # noqa: PLR0917
    a: int, b: int, pa: int, pb: int, start: int, crow: FloatArray, prev: FloatArray,
    prevL: FloatArray, cur: FloatArray, curL: FloatArray, drow: ByteArray,
) -> None:  # fmt: skip
    """One row with path-length weighting: predecessor = argmin (D(p) + c) / (L(p) + 1)."""
    left, left_len = INF, 0.0  # the horizontal predecessor, carried in registers
    for j in range(a, b + 1):
        c = crow[j]
        bs, bd, bl, code = INF, INF, 0.0, NONE
        if pa <= j - 1 <= pb:
            bs = (prev[j - 1] + c) / (prevL[j - 1] + 1.0)
            bd, bl, code = prev[j - 1], prevL[j - 1], DIAG
        if pa <= j <= pb:
            s = (prev[j] + c) / (prevL[j] + 1.0)
            if s < bs:
                bs, bd, bl, code = s, prev[j], prevL[j], UP
        if j > a:
            s = (left + c) / (left_len + 1.0)
            if s < bs:
                bs, bd, bl, code = s, left, left_len, LEFT
        if _starts(j, start) and c < bs:
            bd, bl, code = 0.0, 0.0, START
        left, left_len = c + bd, bl + 1.0
        cur[j], curL[j] = left, left_len
        drow[j] = code


@nb.njit(cache=True, nogil=True)
def _row_argmin(a: int, b: int, cur: FloatArray, curL: FloatArray, plw: bool) -> int:
    """Open-end choice in one row: argmin D (or D / L with path-length weighting); -1 if none."""
    best, arg = INF, -1
    for j in range(a, b + 1):
        v = cur[j] / curL[j] if plw else cur[j]
        if v < best:
            best, arg = v, j
    return arg


@nb.njit(cache=True, nogil=True)
def _store_row(dst: FloatArray, a: int, b: int, src: FloatArray) -> None:
    """dst = src on [a, b] and +inf elsewhere (explicit loops compile much faster than slices)."""
    for j in range(dst.size):
        dst[j] = src[j] if a <= j <= b else INF


@nb.njit(cache=True, nogil=True)
def _row_setup(i: int, lo: IntArray, hi: IntArray, open_begin: bool) -> tuple[int, int, int]:
    """Band (pa, pb) of row i - 1 (empty before the first row) and row i's start code."""
    if i == 0:
        return 0, -1, 2 if open_begin else 1
    return lo[i - 1], hi[i - 1], 0


@nb.njit(cache=True, nogil=True)
def rows_symmetric(  # noqa: PLR0917
    C: FloatArray, i0: int, i1: int, lo: IntArray, hi: IntArray, open_begin: bool, plw: bool,
    D2: FloatArray, L2: FloatArray, dirs: ByteArray, want_dirs: bool, Dfull: FloatArray,
    want_full: bool, omega: IntArray, want_omega: bool,
) -> None:  # fmt: skip
    """Advance the symmetric DP (with back-pointers) over rows i0..i1-1."""
    for i in range(i0, i1):
        a, b = lo[i], hi[i]
        pa, pb, start = _row_setup(i, lo, hi, open_begin)
        cur, prev = D2[i & 1], D2[(i + 1) & 1]
        drow = dirs[i] if want_dirs else dirs[0]
        if plw:
            _row_plw(a, b, pa, pb, start, C[i - i0], prev, L2[(i + 1) & 1], cur, L2[i & 1], drow)
        else:
            _row_plain(a, b, pa, pb, start, C[i - i0], prev, cur, drow)
        if want_full:
            _store_row(Dfull[i], a, b, cur)
        if want_omega:
            omega[i] = _row_argmin(a, b, cur, L2[i & 1], plw)


@nb.njit(cache=True, nogil=True)
def _row_typev(  # noqa: PLR0917
    a: int, b: int, pa: int, pb: int, start: int, crow: FloatArray, P: FloatArray,
    cur: FloatArray, drow: ByteArray,
) -> None:  # fmt: skip
    """One Type V row. P, cur: (3, m) previous / current rows per state (0 free, 1-2 repeats)."""
    for j in range(a, b + 1):
        best, code = INF, NONE
        for k in range(1, 4):
            jp = j - k
            if pa <= jp <= pb:
                for sp in range(3 if k == 1 else 1):
                    if P[sp, jp] < best:
                        best, code = P[sp, jp], 4 * k + sp
        if _starts(j, start) and best > 0.0:
            best, code = 0.0, TV_START
        c = crow[j]
        inside = pa <= j <= pb
        cur[0, j] = c + best
        cur[1, j] = c + P[0, j] if inside else INF
        cur[2, j] = c + P[1, j] if inside else INF
        drow[j] = code


@nb.njit(cache=True, nogil=True)
def _typev_summary(  # noqa: PLR0917
    i: int, a: int, b: int, cur: FloatArray, Dfull: FloatArray, want_full: bool, omega: IntArray,
    want_omega: bool,
) -> None:  # fmt: skip
    """Row i of D = min over states, and the row's open-end argmin."""
    best, arg = INF, -1
    for j in range(a, b + 1):
        v = min(cur[0, j], cur[1, j], cur[2, j])
        if want_full:
            Dfull[i, j] = v
        if v < best:
            best, arg = v, j
    if want_full:
        _store_row(Dfull[i], a, b, Dfull[i])
    if want_omega:
        omega[i] = arg


@nb.njit(cache=True, nogil=True)
def rows_typev(  # noqa: PLR0917
    C: FloatArray, i0: int, i1: int, lo: IntArray, hi: IntArray, open_begin: bool,
    D3: FloatArray, dirs: ByteArray, want_dirs: bool, Dfull: FloatArray, want_full: bool,
    omega: IntArray, want_omega: bool,
) -> None:  # fmt: skip
    """Advance the Type V DP (one x frame per step, y advances 0-3, at most 2 zeros in a row)."""
    for i in range(i0, i1):
        a, b = lo[i], hi[i]
        pa, pb, start = _row_setup(i, lo, hi, open_begin)
        cur = D3[i & 1]
        drow = dirs[i] if want_dirs else dirs[0]
        _row_typev(a, b, pa, pb, start, C[i - i0], D3[(i + 1) & 1], cur, drow)
        if want_full or want_omega:
            _typev_summary(i, a, b, cur, Dfull, want_full, omega, want_omega)


@nb.njit(cache=True, nogil=True)
def backtrack_symmetric(dirs: ByteArray, i: int, j: int, out: IntArray) -> int:
    """Follow back-pointers from (i, j); writes the path reversed into out, returns its length."""
    k = 0
    while k < out.shape[0]:
        out[k, 0], out[k, 1] = i, j
        k += 1
        code = dirs[i, j]
        if code > LEFT:
            break
        i -= 1 if code != LEFT else 0
        j -= 1 if code != UP else 0
    return k


@nb.njit(cache=True, nogil=True)
def backtrack_typev(dirs: ByteArray, i: int, j: int, s: int, out: IntArray) -> int:
    """Type V back-tracking from (i, j) in constraint state s; path written reversed into out."""
    k = 0
    while k < out.shape[0]:
        out[k, 0], out[k, 1] = i, j
        k += 1
        if s > 0:
            i, s = i - 1, s - 1
            continue
        code = dirs[i, j]
        if code >= TV_START:
            break
        i, j, s = i - 1, j - code // 4, code % 4
    return k


@nb.njit(cache=True, nogil=True)
def typev_end_state(D3: FloatArray, i: int, j: int) -> int:
    """Constraint state with the smallest accumulated cost at cell (i, j) of the last row."""
    row = D3[i & 1]
    s = 0
    if row[1, j] < row[s, j]:
        s = 1
    if row[2, j] < row[s, j]:
        s = 2
    return s


@nb.njit(cache=True, nogil=True)
def batch(  # noqa: PLR0917
    C: FloatArray, offsets: IntArray, lo_all: IntArray, hi_all: IntArray, open_begin: bool,
    open_end: bool, plw: bool, typev: bool, want_path: bool, poffs: IntArray, costs: FloatArray,
    paths: IntArray, plens: IntArray, b0: int, b1: int,
) -> None:  # fmt: skip
    """Queries b0..b1-1 against one reference; query b owns rows offsets[b]:offsets[b+1] of C.

    Releases the GIL: the caller runs one slice of queries per thread (a ``prange`` version
    compiles far more slowly for the same speed).
    """
    m = C.shape[1]
    plain = not (open_begin or open_end or plw or want_path or typev)
    for b in range(b0, b1):
        s, e = offsets[b], offsets[b + 1]
        n = e - s
        lo, hi, Cb = lo_all[s:e].copy(), hi_all[s:e].copy(), C[s:e]
        full, omega = np.empty((1, m)), np.empty(n, np.int64)
        dirs = np.empty((n if want_path else 1, m), np.uint8)
        D3, D2 = np.full((2, 3, m), INF), np.full((2, m), INF)
        if typev:
            rows_typev(Cb, 0, n, lo, hi, open_begin, D3, dirs, want_path, full, False, omega, True)
        elif plain:
            rows_cost(Cb, 0, n, lo, hi, D2)
        else:
            rows_symmetric(Cb, 0, n, lo, hi, open_begin, plw, D2, np.ones((2, m)), dirs,
                           want_path, full, False, omega, True)  # fmt: skip
        j = omega[n - 1] if open_end else m - 1
        costs[b], plens[b] = INF, 0
        if lo[n - 1] <= j <= hi[n - 1]:
            st = typev_end_state(D3, n - 1, j) if typev else 0
            costs[b] = D3[(n - 1) & 1, st, j] if typev else D2[(n - 1) & 1, j]
            if want_path and costs[b] < INF:
                out = paths[poffs[b] : poffs[b + 1]]
                if typev:
                    plens[b] = backtrack_typev(dirs, n - 1, j, st, out)
                else:
                    plens[b] = backtrack_symmetric(dirs, n - 1, j, out)
