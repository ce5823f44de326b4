"""Compiled loops behind `analysis.kinematics.quaternions`' product, slerp and relative angle.

The numpy versions build a dozen (N, 4) temporaries per call; over a minute of a 31-joint
recording at 120 fps (2·10⁵ quaternions) that memory traffic, not the arithmetic, is the cost.
These loops compute the same formulas one quaternion at a time on flat (N, 4) arrays; the
broadcasting stays in `quaternions`.
"""

from __future__ import annotations

import numba
import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
# below this sin(ω) the two rotations are the same to float precision: normalised lerp is exact
NEAR_SIN = 1e-9


@numba.njit(cache=True, nogil=True)
def multiply_rows(a: FloatArray, b: FloatArray) -> FloatArray:
    """Hamilton product row by row: (N, 4) × (N, 4) → (N, 4)."""
    out = np.empty_like(a)
    for n in range(a.shape[0]):
        aw, ax, ay, az = a[n, 0], a[n, 1], a[n, 2], a[n, 3]
        bw, bx, by, bz = b[n, 0], b[n, 1], b[n, 2], b[n, 3]
        out[n, 0] = aw * bw - ax * bx - ay * by - az * bz
        out[n, 1] = aw * bx + ax * bw + ay * bz - az * by
        out[n, 2] = aw * by - ax * bz + ay * bw + az * bx
        out[n, 3] = aw * bz + ax * by - ay * bx + az * bw
    return out


@numba.njit(cache=True, nogil=True)
def _slerp_into(a: FloatArray, b: FloatArray, t: float, out: FloatArray) -> None:
    """out = slerp(a, b, t) along the shorter arc, unit (a, b, out: (4,))."""
    dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
    sign = -1.0 if dot < 0.0 else 1.0
    dot = min(abs(dot), 1.0)
    omega = np.arccos(dot)
    sin_omega = np.sin(omega)
    if sin_omega < NEAR_SIN:
        w0, w1 = 1.0 - t, t
    else:
        w0 = np.sin((1.0 - t) * omega) / sin_omega
        w1 = np.sin(t * omega) / sin_omega
    w1 *= sign
    norm = 0.0
    for k in range(4):
        out[k] = w0 * a[k] + w1 * b[k]
        norm += out[k] * out[k]
    norm = np.sqrt(norm)
    for k in range(4):
        out[k] /= norm


@numba.njit(cache=True, nogil=True)
def slerp_rows(q0: FloatArray, q1: FloatArray, t: FloatArray) -> FloatArray:
    """Slerp along the shorter arc row by row: (N, 4), (N, 4), (N,) → (N, 4), unit."""
    out = np.empty_like(q0)
    for n in range(q0.shape[0]):
        _slerp_into(q0[n], q1[n], t[n], out[n])
    return out


@numba.njit(cache=True, nogil=True)
def slerp_between(
    q: FloatArray, lo: npt.NDArray[np.int64], hi: npt.NDArray[np.int64], t: FloatArray
) -> FloatArray:
    """``slerp(q[lo], q[hi], t)`` without gathering q[lo] and q[hi] first: q (L, J, 4), lo and
    hi (F,) indices into L, t (F, J) → (F, J, 4)."""
    n_frames, n_joints = t.shape
    out = np.empty((n_frames, n_joints, 4))
    for f in range(n_frames):
        for j in range(n_joints):
            _slerp_into(q[lo[f], j], q[hi[f], j], t[f, j], out[f, j])
    return out


@numba.njit(cache=True, nogil=True)
def continuous_in_place(q: FloatArray) -> None:
    """Sign flips along time so consecutive quaternions lie in the same hemisphere, in place:
    q (T, M, 4), M series. Each flip is decided on the quaternions as given (the dot product of
    frame t with frame t − 1 before either is flipped, summed in numpy's order), and a series
    keeps its sign until the next flip, as `quaternions.make_continuous` defines it."""
    n_series = q.shape[1]
    sign = np.ones(n_series)
    given = q[0].copy()  # frame t − 1 as given
    for t in range(1, q.shape[0]):
        for m in range(n_series):
            dot = q[t, m, 0] * given[m, 0]
            for k in range(1, 4):
                dot += q[t, m, k] * given[m, k]
            if dot < 0.0:
                sign[m] = -sign[m]
            for k in range(4):
                given[m, k] = q[t, m, k]
                q[t, m, k] *= sign[m]


@numba.njit(cache=True, nogil=True)
def angle_rows(q0: FloatArray, q1: FloatArray) -> FloatArray:
    """Angle (radians, 0..π) of the rotation from q0 to q1 row by row: (N, 4) × 2 → (N,)."""
    out = np.empty(q0.shape[0])
    for n in range(q0.shape[0]):
        aw, ax, ay, az = q0[n, 0], -q0[n, 1], -q0[n, 2], -q0[n, 3]
        bw, bx, by, bz = q1[n, 0], q1[n, 1], q1[n, 2], q1[n, 3]
        w = aw * bw - ax * bx - ay * by - az * bz
        x = aw * bx + ax * bw + ay * bz - az * by
        y = aw * by - ax * bz + ay * bw + az * bx
        z = aw * bz + ax * by - ay * bx + az * bw
        out[n] = 2.0 * np.arctan2(np.sqrt(x * x + y * y + z * z), abs(w))
    return out


@numba.njit(cache=True, nogil=True)
def rotate_rows(q: FloatArray, v: FloatArray) -> FloatArray:
    """Vectors turned by unit quaternions row by row: (N, 4), (N, 3) → (N, 3), as
    v' = v + w·t + u × t with t = 2 u × v."""
    out = np.empty_like(v)
    for n in range(v.shape[0]):
        w, ux, uy, uz = q[n, 0], q[n, 1], q[n, 2], q[n, 3]
        vx, vy, vz = v[n, 0], v[n, 1], v[n, 2]
        tx = 2.0 * (uy * vz - uz * vy)
        ty = 2.0 * (uz * vx - ux * vz)
        tz = 2.0 * (ux * vy - uy * vx)
        out[n, 0] = vx + w * tx + (uy * tz - uz * ty)
        out[n, 1] = vy + w * ty + (uz * tx - ux * tz)
        out[n, 2] = vz + w * tz + (ux * ty - uy * tx)
    return out


@numba.njit(cache=True, nogil=True)
def matrix_rows(q: FloatArray) -> FloatArray:
    """Rotation matrices of unit quaternions row by row: (N, 4) → (N, 3, 3)."""
    out = np.empty((q.shape[0], 3, 3))
    for n in range(q.shape[0]):
        w, x, y, z = q[n, 0], q[n, 1], q[n, 2], q[n, 3]
        xx, yy, zz = x * x, y * y, z * z
        xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
        out[n, 0, 0], out[n, 0, 1], out[n, 0, 2] = 1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)
        out[n, 1, 0], out[n, 1, 1], out[n, 1, 2] = 2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)
        out[n, 2, 0], out[n, 2, 1], out[n, 2, 2] = 2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)
    return out


@numba.njit(cache=True, nogil=True)
def turn_root_relative(q: FloatArray, points: FloatArray) -> FloatArray:
    """Each frame's points relative to its root (joint 0), turned by that frame's unit
    quaternion: q (F, 4), points (F, J, 3) → (F, J, 3) (the same sums as `rotate_rows`)."""
    out = np.empty_like(points)
    for f in range(points.shape[0]):
        w, ux, uy, uz = q[f, 0], q[f, 1], q[f, 2], q[f, 3]
        for j in range(points.shape[1]):
            vx = points[f, j, 0] - points[f, 0, 0]
            vy = points[f, j, 1] - points[f, 0, 1]
            vz = points[f, j, 2] - points[f, 0, 2]
            tx = 2.0 * (uy * vz - uz * vy)
            ty = 2.0 * (uz * vx - ux * vz)
            tz = 2.0 * (ux * vy - uy * vx)
            out[f, j, 0] = vx + w * tx + (uy * tz - uz * ty)
            out[f, j, 1] = vy + w * ty + (uz * tx - ux * tz)
            out[f, j, 2] = vz + w * tz + (ux * ty - uy * tx)
    return out
