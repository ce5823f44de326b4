"""Vectorised rotation helpers: unit quaternions (w, x, y, z), Euler angles and 3×3 matrices.

Every function broadcasts over leading axes: a quaternion array has shape (..., 4), a matrix array
(..., 3, 3), Euler angles (..., 3). Euler angles follow BVH: *intrinsic* rotations in the order
given, so ``order="ZXY"`` with angles (a, b, c) means R = Rz(a)·Rx(b)·Ry(c), the same as
``scipy.spatial.transform.Rotation.from_euler("ZXY", ...)`` with uppercase axes. Euler angles are
in degrees unless ``degrees=False``; rotation vectors and other angles are in radians.
Only Tait-Bryan orders (three different axes) exist in BVH, so only those are supported.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from analysis.kinematics import quaternion_kernels as kernels

FloatArray = npt.NDArray[np.float64]
ArrayLike = npt.ArrayLike

AXES = "XYZ"
_EVEN_ORDERS = ("XYZ", "YZX", "ZXY")
_GIMBAL_EPS = 1e-10


def axis_indices(order: str) -> tuple[tuple[int, int, int], float]:
    """Axis indices of a 3-letter Euler order and its parity (+1 for XYZ, YZX, ZXY, else -1)."""
    order = order.upper()
    if len(order) != 3 or sorted(order) != ["X", "Y", "Z"]:
        raise ValueError(f"Euler order must be a permutation of 'XYZ', got {order!r}")
    i, j, k = (AXES.index(a) for a in order)
    return (i, j, k), (1.0 if order in _EVEN_ORDERS else -1.0)


def complete_order(axes: str) -> str:
    """Extend a partial axis sequence (e.g. 'Z', 'ZX') to a full order with the missing axes."""
    axes = axes.upper()
    return axes + "".join(a for a in AXES if a not in axes)


def identity(shape: tuple[int, ...] = ()) -> FloatArray:
    """Identity quaternions of the given leading shape: (*shape, 4)."""
    q = np.zeros((*shape, 4))
    q[..., 0] = 1.0
    return q


def multiply(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Hamilton product a·b (apply b first, then a): (..., 4) × (..., 4) → (..., 4)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    shape = np.broadcast_shapes(a.shape[:-1], b.shape[:-1])
    flat = kernels.multiply_rows(_rows(a, shape), _rows(b, shape))
    return flat.reshape(*shape, 4)


def _rows(q: FloatArray, shape: tuple[int, ...]) -> FloatArray:
    """(..., 4) broadcast to ``shape`` and laid out as contiguous (N, 4) rows for the kernels."""
    return np.ascontiguousarray(np.broadcast_to(q, (*shape, 4))).reshape(-1, 4)


def conjugate(q: ArrayLike) -> FloatArray:
    """Conjugate (the inverse of a unit quaternion): (..., 4)."""
    out = np.array(q, dtype=np.float64)
    out[..., 1:] *= -1.0
    return out


def normalize(q: ArrayLike) -> FloatArray:
    """Scale quaternions to unit norm: (..., 4)."""
    q = np.asarray(q, dtype=np.float64)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def canonical(q: ArrayLike) -> FloatArray:
    """Choose the sign with w ≥ 0 (q and -q are the same rotation): (..., 4)."""
    q = np.asarray(q, dtype=np.float64)
    return np.where(q[..., :1] < 0.0, -q, q)


def make_continuous(q: ArrayLike, axis: int = 0) -> FloatArray:
    """Flip signs along ``axis`` (time) so consecutive quaternions lie in the same hemisphere."""
    q = np.moveaxis(np.array(q, dtype=np.float64), axis, 0)
    rows = np.ascontiguousarray(q).reshape(q.shape[0], -1, 4)
    kernels.continuous_in_place(rows)
    return np.moveaxis(rows.reshape(q.shape), 0, axis)


def rotate(q: ArrayLike, v: ArrayLike) -> FloatArray:
    """Rotate vectors v (..., 3) by unit quaternions q (..., 4)."""
    q, v = np.asarray(q, dtype=np.float64), np.asarray(v, dtype=np.float64)
    shape = np.broadcast_shapes(q.shape[:-1], v.shape[:-1])
    vectors = np.ascontiguousarray(np.broadcast_to(v, (*shape, 3))).reshape(-1, 3)
    return kernels.rotate_rows(_rows(q, shape), vectors).reshape(*shape, 3)


def _axis_vector(axis: ArrayLike | str) -> FloatArray:
    if isinstance(axis, str):
        return np.eye(3)[AXES.index(axis.upper())]
    return normalize(axis)


def from_axis_angle(axis: ArrayLike | str, angle: ArrayLike) -> FloatArray:
    """Rotation by ``angle`` radians (...,) about ``axis`` ('x', 'y', 'z' or (..., 3) vectors)."""
    axis_vec = _axis_vector(axis)
    half = 0.5 * np.asarray(angle, dtype=np.float64)[..., None]
    vector = np.sin(half) * axis_vec
    scalar = np.broadcast_to(np.cos(half), (*vector.shape[:-1], 1))
    return np.concatenate((scalar, vector), axis=-1)


def from_euler(angles: ArrayLike, order: str, degrees: bool = True) -> FloatArray:
    """Unit quaternions (..., 4) from intrinsic Euler angles (..., 3) in ``order`` (e.g. 'ZXY')."""
    (i, j, k), _ = axis_indices(order)
    half = np.asarray(angles, dtype=np.float64) * (np.pi / 360.0 if degrees else 0.5)
    c, s = np.cos(half), np.sin(half)
    result: FloatArray | None = None
    for n, ax in enumerate((i, j, k)):
        elem = np.zeros((*half.shape[:-1], 4))
        elem[..., 0] = c[..., n]
        elem[..., 1 + ax] = s[..., n]
        result = elem if result is None else multiply(result, elem)
    assert result is not None
    return result


def euler_matrix_components(angles: ArrayLike, order: str, degrees: bool = True) -> FloatArray:
    """Rotation matrices from Euler angles given axis-first: angles (3, ...) → (3, 3, ...).

    The axis-first layout is what forward kinematics wants (contiguous rows over frames). The
    matrix is built in closed form for XYZ and mapped to the requested order by relabelling axes
    (an odd relabelling is a reflection and flips the angles' signs). cos/sin come from the
    tangent half-angle because numpy vectorises ``tan`` with SIMD but not ``sin``/``cos``.
    """
    (i, j, k), sign = axis_indices(order)
    t = np.tan(np.asarray(angles, dtype=np.float64) * (np.pi / 360.0 if degrees else 0.5))
    t2 = t * t
    inv = 1.0 / (1.0 + t2)
    c = (1.0 - t2) * inv
    s = (2.0 * sign) * t * inv
    ca, cb, cc = c
    sa, sb, sc = s
    sasb, casb = sa * sb, ca * sb
    out = np.empty((3, 3, *c.shape[1:]))
    ax = (i, j, k)
    rows = (
        (cb * cc, -cb * sc, sb),
        (ca * sc + sasb * cc, ca * cc - sasb * sc, -sa * cb),
        (sa * sc - casb * cc, sa * cc + casb * sc, ca * cb),
    )
    for r, row in enumerate(rows):
        for col, value in enumerate(row):
            out[ax[r], ax[col]] = value
    return out


def euler_to_matrix(angles: ArrayLike, order: str, degrees: bool = True) -> FloatArray:
    """Rotation matrices (..., 3, 3) from intrinsic Euler angles (..., 3)."""
    comps = euler_matrix_components(np.moveaxis(np.asarray(angles, float), -1, 0), order, degrees)
    return np.moveaxis(comps, (0, 1), (-2, -1))


def matrix_to_euler(m: ArrayLike, order: str, degrees: bool = True) -> FloatArray:
    """Intrinsic Euler angles (..., 3) of rotation matrices (..., 3, 3); middle one in [-90°, 90°].

    At gimbal lock (middle angle ±90°) the third angle is set to 0.
    """
    (i, j, k), sign = axis_indices(order)
    m = np.asarray(m, dtype=np.float64)
    cos_b = np.hypot(m[..., i, i], m[..., i, j])
    b = np.arctan2(m[..., i, k], cos_b)
    locked = cos_b < _GIMBAL_EPS
    a = np.where(
        locked, np.arctan2(m[..., k, j], m[..., j, j]), np.arctan2(-m[..., j, k], m[..., k, k])
    )
    c = np.where(locked, 0.0, np.arctan2(-m[..., i, j], m[..., i, i]))
    out = sign * np.stack((a, b, c), axis=-1)
    return np.degrees(out) if degrees else out


def to_matrix(q: ArrayLike) -> FloatArray:
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4)."""
    q = np.asarray(q, dtype=np.float64)
    shape = q.shape[:-1]
    return kernels.matrix_rows(_rows(q, shape)).reshape(*shape, 3, 3)


def from_matrix(m: ArrayLike) -> FloatArray:
    """Unit quaternions (..., 4), w ≥ 0, of rotation matrices (..., 3, 3)."""
    m = np.asarray(m, dtype=np.float64)
    # Build the candidate from the largest of w², x², y², z² for numerical stability.
    diag = np.stack((m[..., 0, 0], m[..., 1, 1], m[..., 2, 2]), axis=-1)
    trace = diag.sum(axis=-1)
    cands = np.stack(
        (
            np.stack((1 + trace, m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0],
                      m[..., 1, 0] - m[..., 0, 1]), axis=-1),
            np.stack((m[..., 2, 1] - m[..., 1, 2], 1 + 2 * diag[..., 0] - trace,
                      m[..., 0, 1] + m[..., 1, 0], m[..., 0, 2] + m[..., 2, 0]), axis=-1),
            np.stack((m[..., 0, 2] - m[..., 2, 0], m[..., 0, 1] + m[..., 1, 0],
                      1 + 2 * diag[..., 1] - trace, m[..., 1, 2] + m[..., 2, 1]), axis=-1),
            np.stack((m[..., 1, 0] - m[..., 0, 1], m[..., 0, 2] + m[..., 2, 0],
                      m[..., 1, 2] + m[..., 2, 1], 1 + 2 * diag[..., 2] - trace), axis=-1),
        ),
        axis=-2,
    )  # fmt: skip
    best = np.argmax(np.concatenate((trace[..., None], diag), axis=-1), axis=-1)
    q = np.take_along_axis(cands, best[..., None, None], axis=-2)[..., 0, :]
    return canonical(normalize(q))


def to_euler(q: ArrayLike, order: str, degrees: bool = True) -> FloatArray:
    """Intrinsic Euler angles (..., 3) in ``order`` of unit quaternions (..., 4)."""
    return matrix_to_euler(to_matrix(q), order, degrees)


def slerp(q0: ArrayLike, q1: ArrayLike, t: ArrayLike) -> FloatArray:
    """Spherical linear interpolation along the shorter arc; t (...,) in [0, 1] → (..., 4).
    Nearly equal rotations (sin ω < 1e-9) are interpolated linearly, which is exact enough."""
    q0, q1 = np.asarray(q0, dtype=np.float64), np.asarray(q1, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    shape = np.broadcast_shapes(q0.shape[:-1], q1.shape[:-1], t.shape)
    weights = np.ascontiguousarray(np.broadcast_to(t, shape)).reshape(-1)
    flat = kernels.slerp_rows(_rows(q0, shape), _rows(q1, shape), weights)
    return flat.reshape(*shape, 4)


def slerp_indexed(q: ArrayLike, lo: ArrayLike, hi: ArrayLike, t: ArrayLike) -> FloatArray:
    """``slerp(q[lo], q[hi], t)`` for q (L, J, 4), lo and hi (F,) indices into its first axis,
    t (F, J): (F, J, 4), without building q[lo] and q[hi] (a resampling or an offset field)."""
    return kernels.slerp_between(
        np.ascontiguousarray(q, dtype=np.float64),
        np.ascontiguousarray(lo, dtype=np.int64),
        np.ascontiguousarray(hi, dtype=np.int64),
        np.ascontiguousarray(t, dtype=np.float64),
    )


def from_rotvec(v: ArrayLike) -> FloatArray:
    """Unit quaternions (..., 4) from rotation vectors (..., 3): axis × angle in radians."""
    v = np.asarray(v, dtype=np.float64)
    angle = np.linalg.norm(v, axis=-1, keepdims=True)
    # sin(angle/2)/angle written with sinc so that tiny angles stay exact.
    scale = 0.5 * np.sinc(angle / (2.0 * np.pi))
    return np.concatenate((np.cos(0.5 * angle), scale * v), axis=-1)


def to_rotvec(q: ArrayLike) -> FloatArray:
    """Rotation vectors (..., 3), angle in [0, π] radians, of unit quaternions (..., 4)."""
    q = canonical(q)
    norm_v = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(norm_v, q[..., :1])
    scale = np.where(norm_v < 1e-12, 2.0 / np.maximum(q[..., :1], 1e-300), angle)
    return q[..., 1:] * scale / np.where(norm_v < 1e-12, 1.0, norm_v)


def angle_between(q0: ArrayLike, q1: ArrayLike, degrees: bool = False) -> FloatArray:
    """Angle (...,) of the relative rotation from q0 to q1, in [0, π] radians (or degrees)."""
    q0, q1 = np.asarray(q0, dtype=np.float64), np.asarray(q1, dtype=np.float64)
    shape = np.broadcast_shapes(q0.shape[:-1], q1.shape[:-1])
    angle = kernels.angle_rows(_rows(q0, shape), _rows(q1, shape)).reshape(shape)
    return np.degrees(angle) if degrees else angle


def twist_angle(q: ArrayLike, axis: str) -> FloatArray:
    """Signed angle (...,) in (-π, π] of the twist of q about a coordinate axis ('x', 'y', 'z').

    Swing-twist decomposition: q = swing·twist with twist a rotation about ``axis``; for a
    vertical axis this is the heading (yaw) of q.
    """
    q = np.asarray(q, dtype=np.float64)
    comp = q[..., 1 + AXES.index(axis.upper())]
    angle = 2.0 * np.arctan2(comp, q[..., 0])
    return np.angle(np.exp(1j * angle))
