"""Local (frame-to-frame) costs for time warping, with per-joint weights.

A frame is a flat feature vector of length ``d``. Cost kinds:

- ``"euclidean"``: ``sqrt(sum_f w_f (a_f - b_f)^2)``; with per-joint weights ``w`` of length ``J``
  (``d % J == 0``) every joint's ``d / J`` consecutive features share its weight.
- ``"sqeuclidean"``: the same without the square root (what dtaidistance accumulates).
- ``"quaternion"``: ``sum_j w_j (1 - |q_j . q'_j|)`` over ``J = d / 4`` unit quaternions
  ``(w, x, y, z)`` per frame (paper 000, eqs 1 and 4). Range per joint [0, 1].
- ``"geodesic"``: ``sum_j w_j (2/pi) arccos|q_j . q'_j|`` (paper 003, eq 3.16). Range per joint
  [0, 1]. Evaluated as ``(2/pi) * 2 atan2(|a - s b|, |a + s b|)`` with ``s = sign(a . b)``, which
  is the same angle for unit quaternions but does not lose half the digits near zero angle
  (``arccos(1 - 1e-16)`` is already 1.5e-8).

``CostInputs.rows`` is what the DTW code calls for a block of query rows: with 16 features or more
and at least 8 rows, Euclidean costs come from one matrix product (``analysis.dtw.cost_blas``: the
``|a|^2 + |b|^2 - 2 a.b`` expansion on single-threaded BLAS, cells where it could cancel recomputed
exactly); otherwise from ``cost_rows``, the compiled direct form: Euclidean costs four query frames
at a time against cache-sized stretches of the reference (each reference value is loaded once for
four frames, the loops vectorise), quaternion costs joint by joint.
``frame_cost`` is the readable per-pair formula the reference implementation uses;
``speed_insensitive_cost`` re-scores a path by paper 001 eq 17.
"""

from __future__ import annotations

import copy
import math
from typing import Literal, get_args

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.dtw import cost_blas

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
CostKind = Literal["euclidean", "sqeuclidean", "quaternion", "geodesic"]
COST_KINDS: tuple[str, ...] = get_args(CostKind)

# Integer codes for the compiled kernels.
MODE_EUC = 1
MODE_SQ = 2
MODE_QUAT = 3
MODE_GEO = 4

_TWO_OVER_PI = 2.0 / math.pi
_STRETCH = 256  # reference frames per accumulator stretch: 4 x 2 KiB stays in L1


def is_quaternion_kind(kind: str) -> bool:
    """True for the cost kinds whose frames are ``J`` quaternions."""
    return kind in ("quaternion", "geodesic")


def check_kind(kind: str) -> None:
    """Raise ValueError for an unknown cost kind."""
    if kind not in COST_KINDS:
        raise ValueError(f"unknown cost kind {kind!r}; expected one of {COST_KINDS}")


def n_joints(d: int, kind: str, weights: npt.ArrayLike | None = None) -> int:
    """Number of weight groups ('joints') in a d-dimensional frame for this cost kind."""
    check_kind(kind)
    if is_quaternion_kind(kind):
        if d % 4:
            raise ValueError(f"{kind} cost needs 4 numbers per joint, got frames of {d}")
        return d // 4
    if weights is None:
        return d
    n = len(np.atleast_1d(np.asarray(weights)))
    if n == 0 or d % n:
        raise ValueError(f"{n} weights cannot split frames of {d} features into equal joints")
    return n


def joint_weights(d: int, kind: str, weights: npt.ArrayLike | None) -> FloatArray:
    """Per-joint weights (J,), ones when ``weights`` is None; validated (finite, >= 0)."""
    J = n_joints(d, kind, weights)
    if weights is None:
        return np.ones(J)
    w = np.asarray(weights, dtype=np.float64).ravel()
    if w.size != J:
        raise ValueError(f"expected {J} joint weights for {kind} frames of {d}, got {w.size}")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError("joint weights must be finite and non-negative")
    return w


def feature_weights(d: int, kind: str, weights: npt.ArrayLike | None) -> FloatArray:
    """Per-feature weights (d,) for the Euclidean kinds: each joint's weight repeated."""
    w = joint_weights(d, kind, weights)
    return np.repeat(w, d // w.size)


def _quaternion_term(qa: FloatArray, qb: FloatArray, kind: str) -> float:
    dot = float(qa @ qb)
    if kind == "quaternion":
        return 1.0 - min(abs(dot), 1.0)
    s = 1.0 if dot >= 0.0 else -1.0
    angle = 2.0 * math.atan2(float(np.linalg.norm(qa - s * qb)), float(np.linalg.norm(qa + s * qb)))
    return _TWO_OVER_PI * angle


def frame_cost(
    a: npt.ArrayLike, b: npt.ArrayLike, kind: str, weights: npt.ArrayLike | None = None
) -> float:
    """Local cost between two frames a, b: (d,) each. Plain formula, no vectorisation tricks."""
    a = np.asarray(a, dtype=np.float64).ravel()
    b = np.asarray(b, dtype=np.float64).ravel()
    if kind in ("euclidean", "sqeuclidean"):
        sq = float(np.sum(feature_weights(a.size, kind, weights) * (a - b) ** 2))
        return math.sqrt(sq) if kind == "euclidean" else sq
    wj = joint_weights(a.size, kind, weights)
    return sum(
        float(w) * _quaternion_term(a[4 * j : 4 * j + 4], b[4 * j : 4 * j + 4], kind)
        for j, w in enumerate(wj)
    )


class CostInputs:
    """Arrays a compiled kernel needs to evaluate local costs of x (n, d) against y (m, d).

    ``x`` and ``y`` are the features as given, ``yt`` is y transposed to (d, m) so that the inner
    loops over reference frames read contiguous memory, ``wj`` the weights the kernels apply: per
    joint for the quaternion kinds, per feature for weighted Euclidean kinds (``w (a - b)^2``, the
    difference taken before any scaling so that near-identical frames lose no digits), empty when
    unweighted. ``mode`` is the kernel's cost code.
    """

    def __init__(
        self,
        x: FloatArray,
        y: FloatArray,
        kind: str,
        weights: npt.ArrayLike | None,
        blas: bool = True,
    ) -> None:
        d = x.shape[1]
        self.blas = blas
        self.kind = kind
        self.wj, self.root = np.zeros(0), np.zeros(0)
        if is_quaternion_kind(kind):
            self.wj = joint_weights(d, kind, weights)
            self.mode = MODE_QUAT if kind == "quaternion" else MODE_GEO
        else:
            self.mode = MODE_EUC if kind == "euclidean" else MODE_SQ
            if weights is not None:
                self.wj = feature_weights(d, kind, weights)
                self.root = np.sqrt(self.wj)
        self.y = np.ascontiguousarray(y)
        self.yt = np.ascontiguousarray(self.y.T)
        if self.uses_blas:  # scaled reference and its norms, shared by every query block
            ys = self.y * self.root if self.root.size else self.y
            self.ys_t = np.ascontiguousarray(ys.T)
            self.ynorm = np.einsum("jk,jk->j", ys, ys)
        self.x = np.ascontiguousarray(x)

    @property
    def uses_blas(self) -> bool:
        """True when large blocks of Euclidean costs go through a matrix product."""
        euclidean = self.mode in (MODE_EUC, MODE_SQ)
        return self.blas and euclidean and self.y.shape[1] >= cost_blas.MIN_DIM

    def with_query(self, x: FloatArray) -> CostInputs:
        """The same reference and cost with another query x (n, d); the reference is shared."""
        other = copy.copy(self)
        other.x = np.ascontiguousarray(x)
        return other

    def rows(self, i0: int, i1: int, lo: IntArray, hi: IntArray, out: FloatArray) -> FloatArray:
        """Local costs of query rows i0..i1-1 within their bands into out[: i1 - i0]."""
        if self.uses_blas and cost_blas.worth_it(self.x.shape[1], lo[i0:i1], hi[i0:i1]):
            a, b = int(lo[i0:i1].min()), int(hi[i0:i1].max())
            xs = self.x[i0:i1] * self.root if self.root.size else self.x[i0:i1]
            with cost_blas.single_threaded_blas():
                G = np.matmul(xs, self.ys_t[:, a : b + 1])
            cost_blas.finish(G, xs, self.x[i0:i1], self.y, self.ynorm, self.wj, a,
                             self.mode == MODE_EUC, out)  # fmt: skip
        else:
            cost_rows(self.mode, self.x, self.yt, self.wj, 0, i0, i1, lo, hi, out)
        return out


@nb.njit(cache=True, nogil=True)
def _sq_four(  # noqa: PLR0917 - numba functions take positional arguments only
    x: FloatArray, yt: FloatArray, w: FloatArray, i: int, lo: int, hi: int, out: FloatArray,
    euc: bool, acc: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
) -> None:  # fmt: skip
    """Squared (or plain) Euclidean costs of query rows i..i+3 into out[0:4, lo:hi+1];
    w: feature weights (d,) or empty.

    Four separate accumulators: each reference value is loaded once for four rows, and LLVM
    vectorises the inner loop (it does not when they are rows of one 2-D array).
    """
    o0, o1, o2, o3 = acc
    for s in range(lo, hi + 1, _STRETCH):
        L = min(_STRETCH, hi + 1 - s)
        for t in range(L):
            o0[t] = 0.0
            o1[t] = 0.0
            o2[t] = 0.0
            o3[t] = 0.0
        for k in range(x.shape[1]):
            a0, a1, a2, a3 = x[i, k], x[i + 1, k], x[i + 2, k], x[i + 3, k]
            wk = w[k] if w.size else 1.0
            yk = yt[k, s:]
            for t in range(L):
                v = yk[t]
                o0[t] += wk * ((a0 - v) * (a0 - v))
                o1[t] += wk * ((a1 - v) * (a1 - v))
                o2[t] += wk * ((a2 - v) * (a2 - v))
                o3[t] += wk * ((a3 - v) * (a3 - v))
        for r in range(4):
            row, o = out[r, s:], acc[r]
            for t in range(L):
                row[t] = math.sqrt(o[t]) if euc else o[t]


@nb.njit(cache=True, nogil=True)
def _sq_row(  # noqa: PLR0917
    x: FloatArray, yt: FloatArray, w: FloatArray, i: int, lo: int, hi: int, out: FloatArray,
    euc: bool,
) -> None:  # fmt: skip
    for j in range(lo, hi + 1):
        out[j] = 0.0
    for k in range(x.shape[1]):
        xi, wk = x[i, k], w[k] if w.size else 1.0
        for j in range(lo, hi + 1):
            out[j] += wk * ((xi - yt[k, j]) * (xi - yt[k, j]))
    if euc:
        for j in range(lo, hi + 1):
            out[j] = math.sqrt(out[j])


@nb.njit(cache=True, nogil=True)
def _quat_row(  # noqa: PLR0917
    i: int, x: FloatArray, yt: FloatArray, wj: FloatArray, lo: int, hi: int, out: FloatArray
) -> None:
    for j in range(lo, hi + 1):
        out[j] = 0.0
    for jj in range(wj.size):
        a = 4 * jj
        x0, x1, x2, x3 = x[i, a], x[i, a + 1], x[i, a + 2], x[i, a + 3]
        w = wj[jj]
        for j in range(lo, hi + 1):
            dot = x0 * yt[a, j] + x1 * yt[a + 1, j] + x2 * yt[a + 2, j] + x3 * yt[a + 3, j]
            out[j] += w * (1.0 - min(abs(dot), 1.0))


@nb.njit(cache=True, nogil=True)
def _half_angle(a: FloatArray, yt: FloatArray, r: int, j: int) -> float:
    """arccos|a . y_j| for unit quaternions a and y_j = yt[r:r+4, j], accurate near 0."""
    dot = a[0] * yt[r, j] + a[1] * yt[r + 1, j] + a[2] * yt[r + 2, j] + a[3] * yt[r + 3, j]
    s = 1.0 if dot >= 0.0 else -1.0
    dm, dp = 0.0, 0.0
    for k in range(4):
        dm += (a[k] - s * yt[r + k, j]) ** 2
        dp += (a[k] + s * yt[r + k, j]) ** 2
    return 2.0 * math.atan2(math.sqrt(dm), math.sqrt(dp))


@nb.njit(cache=True, nogil=True)
def _geo_row(  # noqa: PLR0917
    i: int, x: FloatArray, yt: FloatArray, wj: FloatArray, lo: int, hi: int, out: FloatArray
) -> None:
    for j in range(lo, hi + 1):
        out[j] = 0.0
    for jj in range(wj.size):
        a = x[i, 4 * jj : 4 * jj + 4]
        w = wj[jj] * _TWO_OVER_PI
        for j in range(lo, hi + 1):
            out[j] += w * _half_angle(a, yt, 4 * jj, j)


@nb.njit(cache=True, nogil=True)
def cost_rows(  # noqa: PLR0917
    mode: int, x: FloatArray, yt: FloatArray, wj: FloatArray, xoff: int, i0: int, i1: int,
    lo: IntArray, hi: IntArray, out: FloatArray,
) -> None:  # fmt: skip
    """Local costs of rows i0..i1-1 (query frames x[xoff + i]) within their bands lo[i]..hi[i]
    into out[i - i0]. Euclidean rows go four at a time over the union of their bands; cells
    outside a row's own band may be written too and are never read."""
    i = i0
    acc = (np.empty(_STRETCH), np.empty(_STRETCH), np.empty(_STRETCH), np.empty(_STRETCH))
    while mode <= MODE_SQ and i + 4 <= i1:
        a, b = lo[i : i + 4].min(), hi[i : i + 4].max()
        _sq_four(x, yt, wj, xoff + i, a, b, out[i - i0 : i - i0 + 4], mode == MODE_EUC, acc)
        i += 4
    for r in range(i, i1):
        a, b, row = lo[r], hi[r], out[r - i0]
        if mode <= MODE_SQ:
            _sq_row(x, yt, wj, xoff + r, a, b, row, mode == MODE_EUC)
        elif mode == MODE_QUAT:
            _quat_row(xoff + r, x, yt, wj, a, b, row)
        else:
            _geo_row(xoff + r, x, yt, wj, a, b, row)


def as_frames(x: npt.ArrayLike, name: str = "x") -> FloatArray:
    """A (n, d) float64 C-contiguous copy-or-view of x; 1-D input becomes (n, 1)."""
    a = np.asarray(x, dtype=np.float64)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"{name} must be a non-empty (frames, features) array, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return np.ascontiguousarray(a)


def cost_matrix(
    x: npt.ArrayLike, y: npt.ArrayLike, kind: str = "euclidean",
    weights: npt.ArrayLike | None = None,
) -> FloatArray:  # fmt: skip
    """Local cost matrix C[i, j] = cost(x[i], y[j]): x (n, d), y (m, d) -> (n, m)."""
    xa, ya = as_frames(x, "x"), as_frames(y, "y")
    if xa.shape[1] != ya.shape[1]:
        raise ValueError(f"x has {xa.shape[1]} features per frame, y has {ya.shape[1]}")
    check_kind(kind)
    n, m = xa.shape[0], ya.shape[0]
    lo, hi = np.zeros(n, np.int64), np.full(n, m - 1, np.int64)
    return CostInputs(xa, ya, kind, weights).rows(0, n, lo, hi, np.empty((n, m)))


def paired_costs(
    a: npt.ArrayLike, b: npt.ArrayLike, kind: str, weights: npt.ArrayLike | None = None
) -> FloatArray:
    """Row-wise local costs cost(a[k], b[k]) for a, b: (K, d) -> (K,)."""
    A = np.atleast_2d(np.asarray(a, dtype=np.float64))
    B = np.atleast_2d(np.asarray(b, dtype=np.float64))
    if kind in ("euclidean", "sqeuclidean"):
        sq = ((A - B) ** 2) @ feature_weights(A.shape[1], kind, weights)
        return np.sqrt(sq) if kind == "euclidean" else sq
    wj = joint_weights(A.shape[1], kind, weights)
    qa, qb = A.reshape(len(A), -1, 4), B.reshape(len(B), -1, 4)
    dot = np.einsum("kjc,kjc->kj", qa, qb)
    if kind == "quaternion":
        return (1.0 - np.minimum(np.abs(dot), 1.0)) @ wj
    s = np.where(dot >= 0.0, 1.0, -1.0)[..., None]
    near, far = np.linalg.norm(qa - s * qb, axis=-1), np.linalg.norm(qa + s * qb, axis=-1)
    return (_TWO_OVER_PI * 2.0 * np.arctan2(near, far)) @ wj


def mean_frame(frames: npt.ArrayLike, kind: str) -> FloatArray:
    """Average of frames (k, d) -> (d,); quaternions sign-aligned per joint and renormalised."""
    F = np.atleast_2d(np.asarray(frames, dtype=np.float64))
    if not is_quaternion_kind(kind):
        return F.mean(axis=0)
    q = F.reshape(len(F), -1, 4)
    signs = np.where(np.einsum("kjc,jc->kj", q, q[0]) >= 0.0, 1.0, -1.0)
    mean = (q * signs[..., None]).mean(axis=0)
    return (mean / np.linalg.norm(mean, axis=-1, keepdims=True)).ravel()


def path_groups(path: IntArray) -> list[tuple[int, int]]:
    """Split a path into runs [start, stop) of cells sharing one j (several i) or one i (several j).

    Scanning from the start, a run extends while the next cell keeps the run's shared index; a
    cell that could start either kind of run starts the one its successor continues (j first).
    """
    cells = np.asarray(path).tolist()  # Python ints: a numpy element read costs ten times more
    groups, s, n = [], 0, len(cells)
    while s < n:
        e = s + 1
        for axis in (1, 0):
            while e < n and cells[e][axis] == cells[s][axis]:
                e += 1
            if e > s + 1:
                break
        groups.append((s, e))
        s = e
    return groups


def speed_insensitive_cost(
    x: FloatArray, y: FloatArray, path: IntArray, kind: str, weights: npt.ArrayLike | None
) -> float:
    """Paper 001 eq 17: each many-to-one run of a path counts once, with the mean of its frames."""
    A, B = [], []
    for s, e in path_groups(path):
        i, j = path[s:e, 0], path[s:e, 1]
        A.append(mean_frame(x[i[0] : i[-1] + 1], kind))
        B.append(mean_frame(y[j[0] : j[-1] + 1], kind))
    return float(paired_costs(np.array(A), np.array(B), kind, weights).sum())
