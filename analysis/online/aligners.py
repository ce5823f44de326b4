"""Streaming (on-line) alignment of a live query to a prerecorded reference, one frame at a time.

``OpenEndAligner`` is Open-End DTW (Tormene et al.), and with ``path_length_weighting=True`` and
optimised joint weights the Weight-Optimized OE-DTW of paper 000: every pushed frame adds one row to
the accumulated cost (O(m) work and memory per frame) and the answer is that row's open-end argmin.
Its answers equal ``align(query[:t+1], reference, replace(options, open_end=True)).end``.

``ForwardPlotAligner`` implements the forward-plotting methods of paper 003 (ch. 5-6): the mapping
never goes backwards, so a tutor played back through it never jumps back in time.

- A: the best-matching reference frame among the next ``search`` frames (greedy).
- B: forecast the query ``window`` frames ahead, DTW between the forecast and the next reference
  frames, read the newest frame's match off the path.
- C: same forecast, costs accumulated backwards from the forecast's far end; the newest frame goes
  to the argmin of the first column.

Corrections from the project's specification: the forecast extrapolates forwards from the velocity
over the last
``history`` (4-8) frames; C's path may end anywhere in the last forecast column. With
``DTWOptions(step="type-v")`` the Type V constraint of 003 ch. 6 (Table 6.3) limits each step:
state A allows 0-3 reference frames forward, B (after one repeat) 0-1, C (after two) exactly 1.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.dtw import (
    CostInputs,
    DTWOptions,
    as_frames,
    cost_rows,
    is_quaternion_kind,
)
from analysis.dtw import kernels as kern
from analysis.kinematics import quaternions as quat

FloatArray = npt.NDArray[np.float64]
_BIG = 1e4  # the "very high value" 003 gives to cells the constraint forbids


class OpenEndAligner:
    """Open-End DTW over a stream: ``push(frame) -> reference index`` for the newest frame.

    reference: (m, d). options: any ``DTWOptions`` (open_end is implied; a window is the band
    ``|j - i| <= window``). Memory: two cost rows plus one byte per reference frame per pushed frame
    for ``path()`` (set ``keep_path=False`` to drop it).
    """

    def __init__(
        self, reference: npt.ArrayLike, options: DTWOptions | None = None, keep_path: bool = True
    ) -> None:
        self.options = replace(options or DTWOptions(), open_end=True, return_matrix=False)
        self.reference = as_frames(reference, "reference")
        m = self.reference.shape[0]
        self._ci = CostInputs(
            self.reference[:1], self.reference, self.options.cost, self.options.weights
        )
        self._typev = self.options.step == "type-v"
        self._D = np.full((2, 3, m) if self._typev else (2, m), np.inf)
        self._L = np.ones((2, m))
        self._crow = np.empty((1, m))
        self._full = np.empty((1, m))
        self._keep = keep_path
        self._lo = self._hi = self._omega = np.zeros(0, np.int64)
        self._dirs: npt.NDArray[np.uint8] = np.zeros((0, m), np.uint8)
        self._grow(64)
        self.t = 0

    def _grow(self, capacity: int) -> None:
        m, n_old = self.reference.shape[0], self._lo.size
        extra = np.zeros(capacity - n_old, np.int64)
        self._lo = np.concatenate([self._lo, extra])
        self._hi = np.concatenate([self._hi, extra])
        self._omega = np.concatenate([self._omega, extra - 1])
        rows = capacity if self._keep else 1
        dirs = np.empty((rows, m), np.uint8)
        if self._keep and n_old:
            dirs[:n_old] = self._dirs
        self._dirs = dirs

    def push(self, frame: npt.ArrayLike) -> int:
        """Add the newest query frame (d,); return the reference frame it matches (open end)."""
        t, m = self.t, self.reference.shape[0]
        if t >= self._lo.size:
            self._grow(2 * self._lo.size)
        w = self.options.window
        self._lo[t] = 0 if w is None else min(max(0, t - w), m)
        self._hi[t] = m - 1 if w is None else min(m - 1, t + w)
        ci = self._ci.with_query(as_frames(np.ravel(frame)[None, :], "frame"))
        cost_rows(ci.mode, ci.x, ci.yt, ci.wj, -t, t, t + 1, self._lo, self._hi, self._crow)
        head = (self._crow, t, t + 1, self._lo, self._hi, bool(self.options.open_begin))
        tail = (self._dirs, self._keep, self._full, False, self._omega, True)
        if self._typev:
            kern.rows_typev(*head, self._D, *tail)
        else:
            plw = bool(self.options.path_length_weighting)
            kern.rows_symmetric(*head, plw, self._D, self._L, *tail)
        self.t += 1
        j = int(self._omega[t])
        # An exhausted Type V band has no admissible cell any more: stay at the reference's end.
        return j if j >= 0 else m - 1

    def row(self) -> FloatArray:
        """Accumulated cost D(t, j) of the newest frame t against every reference frame j: (m,).

        With the default closed begin, ``row()[j]`` is the DTW cost of the query so far against
        ``reference[:j+1]``; +inf outside the band.
        """
        if self.t == 0:
            raise ValueError("nothing pushed yet")
        t = self.t - 1
        last = self._D[t & 1]
        out = np.full(last.shape[-1], np.inf)
        a, b = self._lo[t], self._hi[t]
        out[a : b + 1] = (last.min(axis=0) if self._typev else last)[a : b + 1]
        return out

    def path(self) -> npt.NDArray[np.int64]:
        """Warping path (K, 2) of the frames pushed so far, ending at the latest answer."""
        if not self._keep or self.t == 0:
            raise ValueError("no path: nothing pushed yet, or keep_path=False")
        i, j = self.t - 1, int(self._omega[self.t - 1])
        if j < 0:
            raise ValueError("no admissible warping path for the frames pushed so far")
        out = np.empty((self.t + self.reference.shape[0], 2), np.int64)
        if self._typev:
            k = kern.backtrack_typev(self._dirs, i, j, kern.typev_end_state(self._D, i, j), out)
        else:
            k = kern.backtrack_symmetric(self._dirs, i, j, out)
        return np.ascontiguousarray(out[:k][::-1])


@dataclass(frozen=True)
class ForwardPlotOptions:
    """Settings of the forward-plotting aligners (paper 003, ch. 5).

    method: "A", "B" or "C". window: forecast length w in frames (B, C); about a third of the
    movement cycle is best (40 frames at 120 Hz). search: how many frames ahead A may jump.
    history: frames back used for the forecast velocity (4-8; until that many frames have arrived
    the reference advances one frame per frame).
    """

    method: Literal["A", "B", "C"] = "C"
    window: int = 40
    search: int = 2
    history: int = 6

    def __post_init__(self) -> None:
        if self.method not in ("A", "B", "C"):
            raise ValueError(f"method must be 'A', 'B' or 'C', got {self.method!r}")
        if self.window < 2 or self.search < 1 or self.history < 1:
            raise ValueError("window must be >= 2, search and history >= 1")


_TYPE_V_STEPS = {"A": (0, 1, 2, 3), "B": (0, 1), "C": (1,)}
_TYPE_V_REPEAT = {"A": "B", "B": "C"}


class TypeV:
    """Constraint state table of 003 Table 6.3: state -> allowed steps, (state, step) -> state.

    A step is how many reference frames the mapping advances for one new query frame.
    """

    def __init__(self) -> None:
        self.state = "A"

    def allowed(self) -> tuple[int, ...]:
        """Reference steps allowed for the next query frame."""
        return _TYPE_V_STEPS[self.state]

    def advance(self, k: int) -> None:
        """Record a step of k reference frames."""
        if k not in _TYPE_V_STEPS[self.state]:
            raise ValueError(f"step {k} not allowed in Type V state {self.state}")
        self.state = _TYPE_V_REPEAT[self.state] if k == 0 else "A"


def forecast(recent: FloatArray, steps: int, kind: str) -> FloatArray:
    """Dead-reckoning forecast of the next ``steps`` frames from ``recent`` (s + 1, d), oldest first

    Velocity over the whole history, extrapolated forwards (003 eq 5.2, with the sign error of
    Algorithm 6 corrected). Quaternion frames extrapolate each joint's rotation on the sphere:
    q(t + k) = exp(k w) q(t) with w the mean angular step. Returns (steps, d).
    """
    s = len(recent) - 1
    k = np.arange(1, steps + 1, dtype=np.float64)[:, None]
    last = recent[-1]
    if not is_quaternion_kind(kind) or s == 0:
        v = (last - recent[0]) / max(s, 1)
        return last + k * v
    q0 = np.ascontiguousarray(recent[0], dtype=np.float64).reshape(-1, 4)
    q1 = np.ascontiguousarray(last, dtype=np.float64).reshape(-1, 4)
    return _spin_forward(q0, q1, float(s), steps).reshape(steps, -1)


def forecast_reference(recent: FloatArray, steps: int) -> FloatArray:
    """`forecast` for quaternion frames written with `analysis.kinematics.quaternions` (the
    compiled `_spin_forward` is tested against it)."""
    s = len(recent) - 1
    k = np.arange(1, steps + 1, dtype=np.float64)[:, None]
    q1 = recent[-1].reshape(-1, 4)
    q0 = quat.make_continuous(np.stack([recent[0].reshape(-1, 4), q1]))[0]
    omega = quat.to_rotvec(quat.multiply(q1, quat.conjugate(q0))) / s  # (J, 3) radians per frame
    steps_q = quat.from_rotvec(k[:, :, None] * omega[None])  # (steps, J, 4)
    return quat.multiply(steps_q, q1[None]).reshape(steps, -1)


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
    D[0, 0] = _BIG  # forces the walk through (0, 1) or (1, 0): the newest frame may repeat
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


class ForwardPlotAligner:
    """Forward-plotting on-line alignment (003 methods A, B, C): ``push(frame) -> reference index``.

    reference: (m, d). ``dtw`` supplies the local cost (cost, weights) and, with
    ``step="type-v"``, switches on the Type V constraint. The returned index never decreases.
    """

    def __init__(
        self,
        reference: npt.ArrayLike,
        options: ForwardPlotOptions | None = None,
        dtw: DTWOptions | None = None,
    ) -> None:
        self.options = options or ForwardPlotOptions()
        self.dtw = dtw or DTWOptions(cost="geodesic")
        self.reference = as_frames(reference, "reference")
        self._inputs = CostInputs(
            self.reference[:1], self.reference, self.dtw.cost, self.dtw.weights
        )
        self.type_v = TypeV() if self.dtw.step == "type-v" else None
        self.history: list[FloatArray] = []
        self.mapping: list[int] = []

    def _allowed(self, span: int) -> list[int]:
        steps = self.type_v.allowed() if self.type_v else tuple(range(span + 1))
        return [k for k in steps if k <= span]

    def push(self, frame: npt.ArrayLike) -> int:
        """Add the newest query frame (d,); return its reference frame (never below the last)."""
        f = np.asarray(frame, dtype=np.float64).ravel()
        self.history = [*self.history[-self.options.history :], f]
        m = self.reference.shape[0]
        if not self.mapping:
            self.mapping.append(0)
            return 0
        M = self.mapping[-1]
        k = min(1, m - 1 - M) if len(self.mapping) < self.options.history else self._step(M)
        if self.type_v is not None and M + k < m and k in self.type_v.allowed():
            self.type_v.advance(k)
        self.mapping.append(M + k)
        return M + k

    def _costs(self, M: int, span: int, frames: FloatArray) -> FloatArray:
        """Local costs (span + 1, len(frames)) of reference frames M..M+span against frames:
        `cost_matrix` with the frames as the query against cost inputs of the reference made once
        (every cost kind is symmetric term by term, so the values are the same)."""
        frames = as_frames(frames, "frames")
        if frames.shape[1] != self.reference.shape[1]:
            raise ValueError("the frames and the reference differ in features per frame")
        n, out = frames.shape[0], np.empty((frames.shape[0], self.reference.shape[0]))
        lo, hi = np.full(n, M, np.int64), np.full(n, M + span, np.int64)
        self._inputs.with_query(frames).rows(0, n, lo, hi, out)
        return np.ascontiguousarray(out[:, M : M + span + 1].T)

    def _step(self, M: int) -> int:
        m, opt = self.reference.shape[0], self.options
        if m - 1 <= M:
            return 0
        if opt.method == "A":
            span = min(opt.search, m - 1 - M)
            allowed = self._allowed(span)
            c = self._costs(M, span, self.history[-1][None])[:, 0]
            return allowed[int(np.argmin(c[allowed]))]
        span = min(opt.window, m - 1 - M)
        allowed = self._allowed(span)
        ahead = forecast(
            np.array(self.history), opt.window - (1 if opt.method == "C" else 2), self.dtw.cost
        )
        if opt.method == "C":
            D = reverse_accumulate(
                self._costs(M, span, np.vstack([self.history[-1], ahead])),
                bool(self.dtw.path_length_weighting),
            )
            return allowed[int(np.argmin(D[allowed, 0]))]
        C = self._costs(M, span, np.vstack([self.history[-2], self.history[-1], ahead]))
        forbidden = np.setdiff1d(np.arange(span + 1), allowed)
        C[forbidden, 1] = _BIG
        row = method_b_step(C)
        return min(allowed, key=lambda k: (abs(k - row), k))
