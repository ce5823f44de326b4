"""Compiled steps of the on-line aligners (`analysis.online.aligners`): FP-B and FP-C's
accumulations (paper 003), the rotation forecast, and one frame's open-end row and FP-C step as
single calls from Python (the same kernels in the same order as called one by one, so the
answers are equal bit for bit: `tests/live/test_compiled_live.py`)."""

from __future__ import annotations

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.dtw import cost_rows
from analysis.dtw import kernels as kern

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BIG = 1e4  # the "very high value" 003 gives to cells the constraint forbids


@nb.njit(cache=True, nogil=True)
def _open_end_row(  # noqa: PLR0917 - numba functions take positional arguments only
    mode: int, x: FloatArray, yt: FloatArray, wj: FloatArray, t: int, lo: IntArray,
    hi: IntArray, crow: FloatArray, open_begin: bool, plw: bool, D: FloatArray, L: FloatArray,
    dirs: npt.NDArray[np.uint8], keep: bool, full: FloatArray, omega: IntArray,
) -> None:  # fmt: skip
    """Row t of the symmetric open-end DP for the query frame x (1, d): its local costs, the
    accumulated row and its open-end argmin (omega[t]), in one call from Python: the same
    compiled kernels, in the same order, as called one by one."""
    cost_rows(mode, x, yt, wj, -t, t, t + 1, lo, hi, crow)
    kern.rows_symmetric(crow, t, t + 1, lo, hi, open_begin, plw, D, L, dirs, keep, full, False,
                        omega, True)  # fmt: skip


@nb.njit(cache=True, nogil=True)
def _spin_forward(q0: FloatArray, q1: FloatArray, s: float, steps: int) -> FloatArray:
    """Per joint: the mean angular step w from q0 to q1 over s frames, then exp(k w) q1 for
    k = 1..steps: (steps, J, 4). A single frame is too little work for numpy's overheads."""
    J = q1.shape[0]
    out = np.empty((steps, J, 4))
    for j in range(J):
        aw, ax, ay, az = q1[j, 0], q1[j, 1], q1[j, 2], q1[j, 3]
        bw, bx, by, bz = q0[j, 0], q0[j, 1], q0[j, 2], q0[j, 3]
        if aw * bw + ax * bx + ay * by + az * bz < 0.0:  # the same hemisphere as q1
            bw, bx, by, bz = -bw, -bx, -by, -bz
        # r = q1 * conj(q0)
        rw = aw * bw + ax * bx + ay * by + az * bz
        rx = -aw * bx + ax * bw - ay * bz + az * by
        ry = -aw * by + ax * bz + ay * bw - az * bx
        rz = -aw * bz - ax * by + ay * bx + az * bw
        if rw < 0.0:
            rw, rx, ry, rz = -rw, -rx, -ry, -rz
        norm_v = np.sqrt(rx * rx + ry * ry + rz * rz)
        near = norm_v < 1e-12  # the rotation vector's length over norm_v, safely
        scale = 2.0 / max(rw, 1e-300) if near else 2.0 * np.arctan2(norm_v, rw) / norm_v
        wx, wy, wz = rx * scale / s, ry * scale / s, rz * scale / s
        for k in range(steps):
            vx, vy, vz = (k + 1) * wx, (k + 1) * wy, (k + 1) * wz
            angle = np.sqrt(vx * vx + vy * vy + vz * vz)
            half = 0.5 * angle
            f = np.sin(half) / angle if angle > 1e-12 else 0.5
            cw, cx, cy, cz = np.cos(half), f * vx, f * vy, f * vz
            out[k, j, 0] = cw * aw - cx * ax - cy * ay - cz * az
            out[k, j, 1] = cw * ax + cx * aw + cy * az - cz * ay
            out[k, j, 2] = cw * ay - cx * az + cy * aw + cz * ax
            out[k, j, 3] = cw * az + cx * ay - cy * ax + cz * aw
    return out


@nb.njit(cache=True, nogil=True)
def reverse_accumulate(C: FloatArray, plw: bool) -> FloatArray:
    """Method C's accumulated cost (003 Algorithm 9) with a free end in the last column.

    D[i, w-1] = C[i, w-1];  D[i, j] = C[i, j] + min(D[i+1, j+1], D[i+1, j], D[i, j+1]).
    Rows are reference frames, columns the newest query frame then its forecast. With ``plw`` the
    successor is chosen by mean cost (paper 000 eq 3, run backwards) and D / L is returned: plain
    sums favour starting far ahead, where fewer cells are needed, so C would skip frames.
    """
    R, W = C.shape
    D, L = np.empty((R, W)), np.ones((R, W))
    for i in range(R):
        D[i, W - 1] = C[i, W - 1]
    for j in range(W - 2, -1, -1):
        for i in range(R - 1, -1, -1):
            c = C[i, j]
            bd, bl = D[i, j + 1], L[i, j + 1]
            bs = (bd + c) / (bl + 1.0) if plw else bd
            if i + 1 < R:
                for d, le in ((D[i + 1, j + 1], L[i + 1, j + 1]), (D[i + 1, j], L[i + 1, j])):
                    s = (d + c) / (le + 1.0) if plw else d
                    if s < bs:
                        bs, bd, bl = s, d, le
            D[i, j] = c + bd
            L[i, j] = bl + 1.0
    return D / L if plw else D


@nb.njit(cache=True, nogil=True)
def _forward_accumulate(C: FloatArray) -> FloatArray:
    """Standard DTW accumulation from (0, 0) (003 Algorithm 2)."""
    R, W = C.shape
    D = np.empty((R, W))
    for i in range(R):
        for j in range(W):
            best = 0.0 if i == 0 and j == 0 else np.inf
            if i > 0 and j > 0:
                best = D[i - 1, j - 1]
            if i > 0:
                best = min(best, D[i - 1, j])
            if j > 0:
                best = min(best, D[i, j - 1])
            D[i, j] = C[i, j] + best
    return D


@nb.njit(cache=True, nogil=True)
def method_b_step(C: FloatArray) -> int:
    """Method B (003 Algorithms 5, 7): forward DTW, (0, 0) made expensive, walk back from the far
    corner; return the lowest reference row the path visits in column 1 (the newest frame)."""
    D = _forward_accumulate(C)
    D[0, 0] = BIG  # forces the walk through (0, 1) or (1, 0): the newest frame may repeat
    i, j = C.shape[0] - 1, C.shape[1] - 1
    row = i
    while i > 0 or j > 0:
        if j == 1:
            row = i
        if j == 0 or i == 0:
            i, j = max(i - 1, 0), j if i > 0 else j - 1
            continue
        a, b, c = D[i - 1, j - 1], D[i - 1, j], D[i, j - 1]
        if b < a and b <= c:
            i -= 1
        elif c < a and c < b:
            j -= 1
        else:
            i, j = i - 1, j - 1
    return row if C.shape[1] > 1 else 0


@nb.njit(cache=True, nogil=True)
def _forward_c(  # noqa: PLR0917
    mode: int, q0: FloatArray, q1: FloatArray, s: float, steps: int, yt: FloatArray,
    wj: FloatArray, M: int, span: int, plw: bool, allowed: IntArray, scratch: FloatArray,
) -> int:  # fmt: skip
    """FP-C's step from reference frame M for rotation frames: the newest frame q1 (d,) and its
    forecast from q0, s frames earlier (`forecast`), costs against reference frames M..M+span,
    accumulated backwards (`reverse_accumulate`); the allowed step (at most span) whose first
    column costs least, the first on a tie as ``np.argmin``. scratch: (steps + 1, m)."""
    d, n = q1.size, steps + 1
    for v in range(d):  # as `as_frames` checks the frames (-1: not finite)
        if not (np.isfinite(q0[v]) and np.isfinite(q1[v])):
            return -1
    ahead = _spin_forward(q0.reshape((-1, 4)), q1.reshape((-1, 4)), s, steps).reshape((steps, d))
    frames = np.empty((n, d))
    frames[0] = q1
    frames[1:] = ahead
    lo, hi = np.full(n, M, np.int64), np.full(n, M + span, np.int64)
    cost_rows(mode, frames, yt, wj, 0, 0, n, lo, hi, scratch)
    D = reverse_accumulate(np.ascontiguousarray(scratch[:n, M : M + span + 1].T), plw)
    best, choice = np.inf, -1
    for k in allowed:
        if k <= span and (choice < 0 or D[k, 0] < best):
            best, choice = D[k, 0], k
    return choice
