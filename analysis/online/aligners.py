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
from analysis.online.step_kernels import (
    BIG,
    _forward_c,
    _open_end_row,
    _spin_forward,
    method_b_step,
    reverse_accumulate,
)

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


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
        self._open_begin = bool(self.options.open_begin)
        self._plw = bool(self.options.path_length_weighting)
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
        return self.push_finite(as_frames(np.ravel(frame)[None, :], "frame"))

    def push_finite(self, x: FloatArray) -> int:
        """`push` for a frame already checked: a C-contiguous float64 (1, d) array of finite
        values (a live session's features are; the checks cost more than the row)."""
        t, m = self.t, self.reference.shape[0]
        if t >= self._lo.size:
            self._grow(2 * self._lo.size)
        w = self.options.window
        self._lo[t] = 0 if w is None else min(max(0, t - w), m)
        self._hi[t] = m - 1 if w is None else min(m - 1, t + w)
        ci = self._ci
        if self._typev:
            cost_rows(ci.mode, x, ci.yt, ci.wj, -t, t, t + 1, self._lo, self._hi, self._crow)
            head = (self._crow, t, t + 1, self._lo, self._hi, bool(self.options.open_begin))
            tail = (self._dirs, self._keep, self._full, False, self._omega, True)
            kern.rows_typev(*head, self._D, *tail)
        else:
            _open_end_row(ci.mode, x, ci.yt, ci.wj, t, self._lo, self._hi, self._crow,
                          self._open_begin, self._plw, self._D, self._L, self._dirs, self._keep,
                          self._full, self._omega)  # fmt: skip
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
_STEP_ARRAYS = {state: np.array(steps, np.int64) for state, steps in _TYPE_V_STEPS.items()}


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
        # method C on rotations: one compiled call a frame, over scratch made once
        self._compiled_c = self.options.method == "C" and is_quaternion_kind(self.dtw.cost)
        self._plw = bool(self.dtw.path_length_weighting)
        self._every_step = np.arange(self.options.window + 1, dtype=np.int64)
        self._scratch = np.empty((self.options.window, self.reference.shape[0]))

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
        if self._compiled_c:  # the same steps as below, in one compiled call
            q0, q1 = self.history[0], self.history[-1]
            if q1.size != self.reference.shape[1]:
                raise ValueError("the frames and the reference differ in features per frame")
            steps = _STEP_ARRAYS[self.type_v.state] if self.type_v else self._every_step
            k = _forward_c(self._inputs.mode, q0, q1, float(len(self.history) - 1),
                           opt.window - 1, self._inputs.yt, self._inputs.wj, M, span, self._plw,
                           steps, self._scratch)  # fmt: skip
            if k < 0:
                raise ValueError("frames contains NaN or infinite values")
            return k
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
        C[forbidden, 1] = BIG
        row = method_b_step(C)
        return min(allowed, key=lambda k: (abs(k - row), k))
