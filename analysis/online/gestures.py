"""Gesture-based DTW (paper 001, 4.3) over a live stream: the tutor's gesture (one repetition)
repeated, each end found the moment the e confirming frames have arrived.

`analysis.online.gbdtw.segment` does the same over a finished recording. Here every pushed frame
adds one row to an Open-End DTW against the gesture (O(m) per frame); S(k) is that row's last
cell. A local minimum S(k+1) > S(k) is the gesture's end when the next e frames cost what they
would all matched to the gesture's last frame (eqs 10-11). Frames after the end start the next
gesture (they are replayed into it, so nothing is lost).

Guards the paper does not need (its users start moving at once, at the tutor's pace): a
gesture is at least ``min_frames`` long; one that has not ended after ``max_frames`` ends at its
smallest S, so that a long rest cannot hold the stream forever; and ``accept(start, end)`` may
veto a confirmed end (the live aligner refuses ends in the middle of a movement).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from analysis.dtw import cost_matrix
from analysis.online.aligners import OpenEndAligner
from analysis.online.gbdtw import GBDTWOptions, Gesture, _confirmed, _gesture

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class GestureLimits:
    """Shortest and longest gesture, in frames."""

    min_frames: int
    max_frames: int


class GestureStream:
    """``push(frame) -> gestures ended by this frame`` for a stream of repetitions of ``gesture``.

    gesture: (m, d) tutor frames; frames pushed are (d,) in the same feature space. The gestures
    returned carry stream frame numbers (``start``/``end``, inclusive) and tutor frames 0..m-1.
    """

    def __init__(
        self,
        gesture: npt.ArrayLike,
        options: GBDTWOptions,
        limits: GestureLimits,
        accept: Callable[[int, int], bool] | None = None,
    ) -> None:
        self.accept = accept or (lambda start, end: True)
        self.A = np.asarray(gesture, dtype=np.float64)
        self.options = options
        self.limits = limits
        self.u0 = 0
        self.index = 0
        self._buffer: list[FloatArray] = []
        self._reset()

    def _reset(self) -> None:
        dtw = replace(self.options.dtw, open_end=False, path_length_weighting=False)
        self._oa = OpenEndAligner(self.A, dtw, keep_path=False)
        self._S: list[float] = []
        self._last: list[float] = []
        self._candidate: int | None = None
        self._done = 0

    def push(self, frame: npt.ArrayLike) -> list[Gesture]:
        """Add one frame (d,); return the gestures that ended (usually none, at most a few)."""
        self._buffer.append(np.asarray(frame, dtype=np.float64).ravel())
        ended: list[Gesture] = []
        while self._done < len(self._buffer):
            end = self._step(self._done)
            self._done += 1
            if end is not None:  # the frames after the end are replayed into the next gesture
                ended.append(self._close(end))
        return ended

    def finish(self) -> Gesture | None:
        """End of stream: the open gesture ends at its smallest S (eq 9), if it is long enough."""
        if len(self._S) < self.limits.min_frames:
            return None
        lo = self.limits.min_frames - 1
        return self._close(lo + int(np.argmin(self._S[lo:])))

    def _step(self, k: int) -> int | None:
        """Process buffered frame k; the relative end frame if the gesture ended."""
        frame = self._buffer[k]
        self._oa.push(frame)
        S = self._S
        S.append(float(self._oa.row()[-1]))
        self._last.append(float(cost_matrix(self.A[-1:], frame[None], *self._cost())[0, 0]))
        e, lim = self.options.confirm_frames, self.limits
        if self._candidate is None and k >= lim.min_frames and S[k] > S[k - 1]:
            self._candidate = k - 1
        c = self._candidate
        if c is not None and k == c + e:
            confirmed = _confirmed(
                np.array(S), np.array(self._last), c, e, self.options.relative_error
            )
            if confirmed and self.accept(self.u0, self.u0 + c):
                return c
            later = (j for j in range(c + 1, k) if S[j + 1] > S[j] and j >= lim.min_frames - 1)
            self._candidate = next(later, None)
        if k + 1 >= lim.max_frames:
            lo = lim.min_frames - 1
            return lo + int(np.argmin(S[lo:]))
        return None

    def _cost(self) -> tuple[str, tuple[float, ...] | None]:
        return self.options.dtw.cost, self.options.dtw.weights

    def _close(self, end: int) -> Gesture:
        B = np.array(self._buffer[: end + 1])
        g = _gesture(self.A, B, B, index=self.index, a0=0, u0=self.u0, opt=self.options)
        self._buffer = self._buffer[end + 1 :]
        self.u0 += end + 1
        self.index += 1
        self._reset()
        return g
