"""Quaternion cost matrices for many joint weightings of the same frames (the CMA-ES fit).

The quaternion cost of a frame pair is ``sum_j w_j (1 - min(|q_j . q'_j|, 1))``: only the
weights change between CMA-ES's fitness evaluations, the per-joint terms do not. `JointTerms`
computes each joint's term matrix once (the same dot products, in the same order, as
`analysis.dtw.frame_costs`' quaternion rows); `JointTerms.costs` then sums ``w_j`` times them
joint by joint, starting from 0.0 as those rows do, so every cell has the bits `cost_matrix`
gives for those weights, for a multiply-add per joint and cell instead of a dot product.
"""

from __future__ import annotations

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.dtw.frame_costs import cost_matrix, joint_weights

FloatArray = npt.NDArray[np.float64]
MAX_TERM_BYTES = 64 << 20  # above this the terms would cost more memory than they save time


@nb.njit(cache=True, nogil=True)
def _terms(x: FloatArray, yt: FloatArray) -> FloatArray:
    """(J, n, m): 1 - min(|q_j . q'_j|, 1) of query frames x (n, 4J) against reference frames
    yt (4J, m), each dot product summed as `frame_costs._quat_row` sums it."""
    n, m, J = x.shape[0], yt.shape[1], x.shape[1] // 4
    out = np.empty((J, n, m))
    for i in range(n):
        for jj in range(J):
            a = 4 * jj
            x0, x1, x2, x3 = x[i, a], x[i, a + 1], x[i, a + 2], x[i, a + 3]
            for j in range(m):
                dot = x0 * yt[a, j] + x1 * yt[a + 1, j] + x2 * yt[a + 2, j] + x3 * yt[a + 3, j]
                out[jj, i, j] = 1.0 - min(abs(dot), 1.0)
    return out


@nb.njit(cache=True, nogil=True)
def _weighted(terms: FloatArray, w: FloatArray) -> FloatArray:
    """(n, m): sum over joints of w_j terms_j, in joint order from 0.0."""
    J, n, m = terms.shape
    out = np.zeros((n, m))
    for jj in range(J):
        wj = w[jj]
        for i in range(n):
            for j in range(m):
                out[i, j] += wj * terms[jj, i, j]
    return out


class JointTerms:
    """One recording's per-joint quaternion terms against the reference (or, when they would
    take more than `MAX_TERM_BYTES`, nothing: ``costs`` then calls `cost_matrix`)."""

    def __init__(self, x: FloatArray, y: FloatArray) -> None:
        self.x, self.y = x, y
        size = x.shape[0] * y.shape[0] * (x.shape[1] // 4) * 8
        fits = size <= MAX_TERM_BYTES and x.shape[1] % 4 == 0
        self.terms = _terms(x, np.ascontiguousarray(y.T)) if fits else None

    def costs(self, weights: FloatArray) -> FloatArray:
        """`cost_matrix(x, y, "quaternion", weights)`, with the same bits."""
        if self.terms is None:
            return cost_matrix(self.x, self.y, "quaternion", weights)
        w = joint_weights(self.x.shape[1], "quaternion", weights)  # validated as there
        return _weighted(self.terms, np.ascontiguousarray(w, dtype=np.float64))
