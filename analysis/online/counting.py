"""Repetitions counted on a live progress signal by the offline segmenter's own rules.

The offline analysis cuts a recording at the peaks of its cleaned progress signal
(`analysis.landmarks.segmentation`): a median filter and a Hann window (an eighth and a twelfth
of the tutor's repetition wide), heights above the recording's rest level, peaks that stand out
by `MIN_PROMINENCE` and by `RELATIVE_PROMINENCE` of their height, `MIN_SPACING` apart. Here the
same cleaning runs one frame at a time, ``lag`` frames behind the newest frame (the filters'
half widths: the look-ahead they need), and a peak counts the moment the cleaned signal after it
has fallen by that prominence and come back near rest (`REST_FRACTION` of its height, or the next
movement has begun). The rest level is the 5th percentile of the cleaned signal so far. At the
end of the stream the filters are flushed with the offline edge rules (zeros for the median,
the last value for the Hann window) and the signal is padded with the rest level, so a
repetition cut off by the end still counts, as offline.

Offline, the key poses also vote: a peak none of them confirms counts only if it rises to 60 %
of the confirmed ones, and a key pose's end of range in a gap wide enough for two repetitions
adds one there. Live there are no key poses (their features need frames on both sides): every
peak that passes the tests above and rises `MIN_PROMINENCE` above rest counts, unless it stays
below `LOW_HEIGHT` of the counted peaks' median height (once three are counted) or is a low
first peak the stream began after (`UNSEEN_RISE`); in a gap of `GAP_FACTOR` times the median
spacing of the repetitions so far (once three are counted) the clearest hump counts too
(`bench/eval_live.py`, docs/sections/eval_live.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.signal import find_peaks

from analysis.landmarks.segmentation import (
    GAP_FACTOR,
    MIN_PROMINENCE,
    MIN_SPACING,
    REST_FRACTION,
    REST_PERCENTILE,
    REST_SPLIT,
    clean_progress,
    middle_of_rest,
)
from analysis.landmarks.segmentation import RELATIVE_PROMINENCE as RELATIVE
from analysis.online.peaks import percentile, prominent_peaks

FloatArray = npt.NDArray[np.float64]
HISTORY_REPS = 3.0  # repetitions of cleaned signal searched for peaks (older ones are counted)
LOW_HEIGHT = 0.3  # of the counted peaks' median height: lower peaks are twitches (live rule)
UNSEEN_RISE = 0.5  # tutor units: a first peak whose rise the stream missed counts from here


@dataclass(frozen=True)
class Counted:
    """One repetition found live: frames of the progress stream (start, end-of-range peak,
    end, inclusive) and how high the peak rose above the rest level (tutor units)."""

    start: int
    peak: int
    end: int
    height: float


class Growing:
    """A float array that grows by appending (amortised O(1)), viewed as ``values``."""

    def __init__(self) -> None:
        self._data = np.zeros(256)
        self.size = 0

    def append(self, value: float) -> None:
        if self.size == self._data.size:
            self._data = np.concatenate([self._data, np.zeros(self._data.size)])
        self._data[self.size] = value
        self.size += 1

    @property
    def values(self) -> FloatArray:
        return self._data[: self.size]


class RepetitionCounter:
    """``push(progress) -> repetitions ended`` over a progress stream, one value per frame.

    rep_frames: the tutor's repetition length in frames (sets every width and distance).
    """

    def __init__(self, rep_frames: float) -> None:
        self.rep = float(rep_frames)
        self._half = max(int(self.rep / 8), 0)  # median filter half width
        width = max(int(self.rep / 12), 1)
        kernel = np.hanning(width + 2)[1:-1] if width >= 2 else np.ones(1)
        self._kernel = (kernel / kernel.sum())[::-1]
        # np.convolve(..., "same") centres an even kernel one frame late
        self._before, self._after = len(kernel) // 2, (len(kernel) - 1) // 2
        self.lag = self._half + self._after
        self._distance = max(int(MIN_SPACING * self.rep), 1)
        self._pad = max(int(self.rep / 4), 1)  # offline pads the signal's ends this much
        self.raw = Growing()
        self._median = Growing()
        self.clean = Growing()  # the cleaned signal, `lag` frames behind `raw`
        self._low = 0.0  # least cleaned value so far (offline pads the ends with it, or 0)
        self._top = -np.inf  # highest cleaned value since the last repetition ended
        self._rest: float | None = None
        self.counted: list[Counted] = []
        self._pending: tuple[int, float] | None = None  # a confirmed peak not yet back at rest
        self._next_peak: int | None = None  # the peak after a pending one found in a gap
        self._cut = False  # the last repetition ended where the rest before the next is split

    # --- cleaning -----------------------------------------------------------------------------

    def push(self, value: float) -> list[Counted]:
        """Add the newest frame's progress; return the repetitions that ended with it."""
        self.raw.append(float(value))
        j = self.raw.size - 1 - self._half  # its median-filter window is complete
        if j >= 0:
            self._median.append(self._median_at(j))
        k = self._median.size - 1 - self._after  # its Hann window is complete
        if k >= 0:
            self._add_clean(self._smooth_at(k))
            return self._step(final=False)
        return []

    def finish(self) -> list[Counted]:
        """End of stream: flush the filters (offline edge rules), then the last repetition."""
        n = self.raw.size
        if n <= 2 * self._half + 1 or n < len(self._kernel):  # offline filters less: start again
            self._median, self.clean = Growing(), Growing()
            for value in clean_progress(self.raw.values, self.rep).tolist():
                self._median.append(value)
                self._add_clean(value)
        while self._median.size < n:
            self._median.append(self._median_at(self._median.size))
        ended: list[Counted] = []
        while self.clean.size < n:
            self._add_clean(self._smooth_at(self.clean.size))
            ended += self._step(final=False)
        return ended + self._step(final=True) if n else ended

    def _add_clean(self, value: float) -> None:
        self.clean.append(value)
        self._low = min(self._low, value) if self.clean.size > 1 else value
        self._top = max(self._top, value)

    def _median_at(self, j: int) -> float:
        """medfilt's value at frame j (zeros outside the stream, as scipy pads)."""
        raw = self.raw.values
        lo, hi = j - self._half, j + self._half + 1
        window = raw[max(lo, 0) : hi].tolist()
        window += [0.0] * (max(0, -lo) + max(0, hi - raw.size))
        # an odd count (2 half + 1): the middle value; sorting a short list beats np.median
        return float(sorted(window)[self._half])

    def _smooth_at(self, k: int) -> float:
        """The Hann window's value at frame k (edge values repeated, as offline)."""
        median = self._median.values
        lo, hi = k - self._before, k + self._after + 1
        if lo >= 0 and hi <= median.size:
            return float(median[lo:hi] @ self._kernel)
        idx = np.clip(np.arange(lo, hi), 0, median.size - 1)
        return float(median[idx] @ self._kernel)

    # --- peaks --------------------------------------------------------------------------------

    def _rest_level(self) -> float:
        """The 5th percentile of the cleaned signal so far (updated every few frames)."""
        if self._rest is None or self.clean.size % 8 == 0:
            self._rest = percentile(self.clean.values, REST_PERCENTILE)
        return self._rest

    def _step(self, final: bool) -> list[Counted]:
        """Look for a newly confirmed peak; emit the pending one once it is back at rest."""
        rest = self._rest_level()
        ended: list[Counted] = []
        # a new peak is confirmed only once the signal has fallen by the least prominence
        falling = self._top - self.clean.values[-1] >= MIN_PROMINENCE
        if self._pending is None and (falling or final):
            self._pending = self._confirmed_peak(rest, final)
        if self._pending is not None and (final or self._back_at_rest(rest)):
            ended.append(self._emit(rest, final))
        while final:  # the last peaks need no return to rest: the stream has ended
            self._pending = self._confirmed_peak(rest, final)
            if self._pending is None:
                break
            ended.append(self._emit(rest, final))
        return ended

    def _confirmed_peak(self, rest: float, final: bool) -> tuple[int, float] | None:
        """The first peak after the last counted one that passes the offline tests on the
        signal so far (at the end: padded with the rest level, as offline)."""
        n = self.clean.size
        after = self.counted[-1].peak if self.counted else -1
        lo = max(0, n - int(HISTORY_REPS * self.rep), after - self._distance)
        window = self.clean.values[lo:] - rest
        pad, floor = self._pad, min(self._low - rest, 0.0)
        left, right = (pad if lo == 0 else 0), (pad if final else 0)
        peaks, prominences = prominent_peaks(window, left, right, floor, self._distance)
        for p, prominence in zip(peaks, prominences, strict=True):
            frame = min(max(lo + p - left, 1), max(n - 2, 1))
            h = float(self.clean.values[frame] - rest)
            if frame <= after or prominence < RELATIVE * max(h, 1e-9) or h < MIN_PROMINENCE:
                continue  # a repetition rises above the rest level, and stands out
            if self.counted and frame - after < self._distance:
                continue  # counted already, or a higher one offline keeps (distance rule)
            if self._too_low(frame, h):
                continue
            return self._gap_peak(after, frame, rest) or (frame, h)
        return None

    def _too_low(self, frame: int, h: float) -> bool:
        """Offline, a peak no key pose confirms counts only if it rises to `UNCONFIRMED_HEIGHT`
        of the confirmed ones; live, a peak below `LOW_HEIGHT` of the counted ones' median
        (once three are counted), or a first peak at the stream's start (its rise unseen: the
        stream began on the way down) below `UNSEEN_RISE`, is a twitch."""
        if len(self.counted) >= 3:
            return h < LOW_HEIGHT * float(np.median([c.height for c in self.counted]))
        if self.counted or h >= UNSEEN_RISE:
            return False
        before = self.clean.values[: max(frame, 1)]  # its rise: a prominence below the peak
        return bool(before.min() > self.clean.values[frame] - MIN_PROMINENCE)

    def _gap_peak(self, after: int, frame: int, rest: float) -> tuple[int, float] | None:
        """Offline, a key pose's end of range in a gap between peaks wide enough for two
        repetitions adds one there, half a spacing from either side: live, the clearest hump
        (half the usual prominence) in such a gap before the peak at ``frame``."""
        if len(self.counted) < 3:  # one spacing says too little about the patient's pace
            return None
        spacing = float(np.median(np.diff([c.peak for c in self.counted])))
        if frame - after <= GAP_FACTOR * spacing:
            return None
        # up to a quarter spacing before the next peak: the trough after the hump is inside
        lo, hi = after + int(np.ceil(0.5 * spacing)), frame - int(np.ceil(0.25 * spacing))
        if hi <= lo:
            return None
        window = self.clean.values[lo : hi + 1] - rest
        peaks, props = find_peaks(window, prominence=0.5 * MIN_PROMINENCE)
        if peaks.size == 0:
            return None
        best = int(peaks[int(np.argmax(props["prominences"]))])
        self._next_peak = frame
        return lo + best, float(window[best])

    def _back_at_rest(self, rest: float) -> bool:
        """Is the cleaned signal back near rest after the pending peak, or rising again?"""
        assert self._pending is not None
        peak, h = self._pending
        after = self.clean.values[peak:] - rest
        low = float(after.min())
        if after[-1] <= low + REST_FRACTION * (h - low) and after[-1] <= REST_FRACTION * h:
            return True
        return self._rising(after)

    @staticmethod
    def _rising(after: FloatArray) -> bool:
        """Has the next movement begun (risen again from the lowest point since the peak)?"""
        return bool(after[-1] - after.min() >= 0.5 * MIN_PROMINENCE)

    def _emit(self, rest: float, final: bool) -> Counted:
        """The pending peak as a repetition: from the middle of the rest before it to now."""
        assert self._pending is not None
        peak, h = self._pending
        self._pending = None
        start = self._start_before(rest, peak)
        end = self.raw.size - 1 if final else self.clean.size - 1
        self._cut = False
        height = self.clean.values - rest
        if self._next_peak is not None:  # ends where the rest before the next one is split
            end, self._cut = middle_of_rest(height, peak, self._next_peak) - 1, True
            self._next_peak = None
        elif not final and self._rising(height[peak:]):  # ends at the trough
            end = peak + int(np.argmin(height[peak:]))
        counted = Counted(start, peak, max(end, peak), h)
        self.counted.append(counted)
        later = self.clean.values[counted.end + 1 :]
        self._top = float(later.max()) if later.size else -np.inf
        return counted

    def _start_before(self, rest: float, peak: int) -> int:
        """Where the rest before ``peak`` is split (`REST_SPLIT` of it), after the previous
        repetition's end; the first repetition starts a sixth of a repetition before its
        onset."""
        previous = self.counted[-1] if self.counted else None
        floor = min(previous.end + 1, peak - 1) if previous is not None else 0
        if self._cut:
            return floor
        before = self.clean.values[floor : peak + 1] - rest
        low = float(before.min())
        resting = np.flatnonzero(before <= low + REST_FRACTION * (before[-1] - low))
        if previous is None:
            onset = int(resting[-1]) if resting.size else 0
            return max(0, min(onset - int(self.rep / 6), peak - 1))
        return floor + round(resting[0] + REST_SPLIT * (resting[-1] - resting[0]))
