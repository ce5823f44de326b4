"""Compiled loops over joint positions (bone lengths, angles between segments) for a whole
recording: the numpy versions gather (F, n, 3) copies of the points for every term, and on a
minute at 120 fps that memory traffic costs more than the arithmetic. Same formulas, one frame
at a time; the callers in `analysis.kinematics` keep their readable numpy reductions around them.
"""

from __future__ import annotations

import numba
import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
# below this product of segment lengths the angle is meaningless: cos is taken as 0 there
TINY = 1e-12


@numba.njit(cache=True, nogil=True)
def distances(points: FloatArray, a: IntArray, b: IntArray) -> FloatArray:
    """|points[:, a[k]] − points[:, b[k]]| for every frame and k: (F, P, 3) → (F, K)."""
    out = np.empty((points.shape[0], a.shape[0]))
    for f in range(points.shape[0]):
        for k in range(a.shape[0]):
            x = points[f, a[k], 0] - points[f, b[k], 0]
            y = points[f, a[k], 1] - points[f, b[k], 1]
            z = points[f, a[k], 2] - points[f, b[k], 2]
            out[f, k] = np.sqrt(x * x + y * y + z * z)
    return out


@numba.njit(cache=True, nogil=True)
def angles_at(points: FloatArray, a: IntArray, b: IntArray, c: IntArray) -> FloatArray:
    """Angle (radians) at b[k] between b→a[k] and b→c[k] in every frame: (F, P, 3) → (F, K)."""
    out = np.empty((points.shape[0], a.shape[0]))
    for f in range(points.shape[0]):
        for k in range(a.shape[0]):
            dot, uu, vv = 0.0, 0.0, 0.0
            for d in range(3):
                u = points[f, a[k], d] - points[f, b[k], d]
                v = points[f, c[k], d] - points[f, b[k], d]
                dot += u * v
                uu += u * u
                vv += v * v
            cos = dot / max(np.sqrt(uu) * np.sqrt(vv), TINY)
            out[f, k] = np.arccos(min(max(cos, -1.0), 1.0))
    return out
