"""Repetition boundaries from the main movement axis of the tutor (a fast, robust segmenter).

The tutor's movement relative to its starting pose is summarised by its first principal component:
the *progress* signal rises from the start pose to the end of range and falls back. Projecting a
patient's pose features on the same axis gives their progress signal, in tutor units (0 at the
tutor's start pose, about 1 at its end of range).

Repetitions are the signal's peaks that stand out twice over: by at least `MIN_PROMINENCE` tutor
units (so sensor jitter in a rest pose never counts, whatever the patient's range), and by at least
`RELATIVE_PROMINENCE` of their own height above the recording's rest level (so a patient who only
half returns between two humps of one repetition, as in sit-to-stand, is not counted twice, while
a patient with a small range still is); and they rise `MIN_PROMINENCE` above the rest level (the
live counter's rule as well), so that the return to rest of a take that ends below it, a lifter
stepping out of the rack, is no repetition. A median filter first removes the one-frame spikes of
optical and depth sensors, and the recording's ends are padded with its rest level so that a
repetition cut off by the end of the recording still counts.

A repetition *starts* in the middle of the rest before it: between the frame where the previous
repetition is back near rest (within `REST_FRACTION` of the lower of the two peaks above the
trough) and the frame where this one leaves it. That is where a person cutting a recording into
repetitions by hand puts the cut (the UI-PRMD episode boundaries sit there: within ±5 frames for
95 % of them, against 70 % for the lowest point of the trough), and it does not move with where
in a flat rest the signal's noise happens to be lowest. The first repetition starts, and the last
ends, half of the recording's typical rest (measured between its repetitions) away from their own
movement, clipped to the recording.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.signal import find_peaks, medfilt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

MIN_PROMINENCE = 0.12  # tutor units: 12 % of the tutor's range of movement
RELATIVE_PROMINENCE = 0.45  # of a peak's height above the rest level
MIN_SPACING = 0.45  # of the tutor's repetition length between two peaks
REST_FRACTION = 0.3  # of the peak's height above the trough: still resting below this
REST_PERCENTILE = 5.0  # the recording's rest level: this percentile of the smoothed signal
# The UI-PRMD episode cuts sit a little before the middle of the rest (within ±5 frames for
# 96.8 % of them at 45 %, 95.5 % at 50 %; measured on the development subjects s02–s07).
REST_SPLIT = 0.45
UNCONFIRMED_HEIGHT = 0.6  # of the confirmed peaks' median height: a peak no key pose confirms
GAP_FACTOR = 1.6  # spacings: a gap this wide between peaks holds a repetition the axis missed
# A key pose the axis has no peak for marks a missed repetition only where the axis moves near it:
# the signal rises there by half `MIN_PROMINENCE` (the live counter's bar for a hump in a gap) and
# by `MISSED_SHARE` of the kept peaks' median height. A phone video's standing pauses wobble by
# 2-3 % of its squats (the classifier still finds "end of range" poses in them); UI-PRMD's one
# missed repetition so rescued (m08 s05, a short one) rises by 14 %.
MISSED_SHARE = 0.1


@dataclass(frozen=True, eq=False)
class ProgressAxis:
    """Mean start pose and unit movement direction in feature space; progress of the tutor's
    end-of-range poses is about 1."""

    start_pose: FloatArray
    direction: FloatArray
    scale: float
    rep_frames: float

    def progress(self, features: FloatArray) -> FloatArray:
        """Progress signal of (F, D) feature rows: (F,), 0 at the start pose, ~1 at end of range."""
        return (features - self.start_pose) @ self.direction / self.scale


def fit_axis(features: FloatArray, starts: IntArray, peaks: IntArray) -> ProgressAxis:
    """The progress axis of a tutor from its feature rows and its start / end-of-range frames."""
    start_pose = features[starts].mean(axis=0)
    moved = features - start_pose
    _, _, vt = np.linalg.svd(moved - moved.mean(axis=0), full_matrices=False)
    direction = vt[0]
    if np.mean(moved[peaks] @ direction) < 0:
        direction = -direction
    scale = float(np.mean(moved[peaks] @ direction)) or 1.0
    rep_frames = float(np.median(np.diff(starts))) if starts.size > 1 else float(features.shape[0])
    return ProgressAxis(start_pose, direction, scale, rep_frames)


@dataclass(frozen=True, eq=False)
class Segments:
    """Repetition starts (R,), ends (R,) and end-of-range frames (R,) in recording frames."""

    starts: IntArray
    ends: IntArray
    peaks: IntArray


def _smooth(signal: FloatArray, width: int) -> FloatArray:
    if width < 2 or signal.size < width:
        return signal
    kernel = np.hanning(width + 2)[1:-1]
    padded = np.pad(signal, width, mode="edge")
    return np.convolve(padded, kernel / kernel.sum(), mode="same")[width:-width]


def clean_progress(progress: FloatArray, rep_frames: float) -> FloatArray:
    """The progress signal without one-frame spikes (median filter) and smoothed (Hann window),
    both about an eighth / a twelfth of a repetition wide."""
    half = max(int(rep_frames / 8), 0)
    despiked = medfilt(progress, 2 * half + 1) if progress.size > 2 * half + 1 else progress
    return _smooth(despiked, max(int(rep_frames / 12), 1))


def find_repetition_peaks(
    height: FloatArray, rep_frames: float, relative: float = RELATIVE_PROMINENCE
) -> IntArray:
    """End-of-range frames: peaks of ``height`` (signal above the rest level) that stand out by
    `MIN_PROMINENCE` and by ``relative`` of their height, `MIN_SPACING` apart."""
    pad = max(int(rep_frames / 4), 1)
    padded = np.pad(height, pad, mode="constant", constant_values=min(float(height.min()), 0.0))
    peaks, props = find_peaks(
        padded, distance=max(int(MIN_SPACING * rep_frames), 1), prominence=MIN_PROMINENCE
    )
    # a peak on the first or last frame moves one frame in, so a repetition's start, peak and end
    # stay three distinct frames (landmarks must be)
    peaks = np.clip(peaks - pad, 1, max(height.size - 2, 1))
    keep = props["prominences"] >= relative * np.maximum(height[peaks], 1e-9)
    # above the rest level too: a take that ends (or starts) below its rest, the lifter stepping
    # out of the rack, makes the return to rest prominent against the padding
    keep &= height[peaks] >= MIN_PROMINENCE
    return np.unique(peaks[keep]).astype(np.int64)


def fuse_peaks(height: FloatArray, key_peaks: IntArray, rep_frames: float) -> IntArray:
    """End-of-range frames agreed between the progress axis and the key poses.

    The progress axis rarely misses a clear peak but may merge two repetitions into one hump or
    count a twitch; the key poses count cycles but may miss or split one. So every clear peak of
    the axis (`find_repetition_peaks`) that a key-pose end of range confirms within a third of a
    repetition is kept; an unconfirmed one only if it rises at least `UNCONFIRMED_HEIGHT` of the
    confirmed peaks' median height (of all the clear peaks' when none is confirmed); and a
    key-pose end of range the axis has no peak for is added where it falls in a gap between kept
    peaks wide enough for two repetitions (`GAP_FACTOR` times their median spacing), at least
    half a spacing from either side, and where the axis moves near it (`moves_near`): a key pose
    in a still rest is no repetition.
    """
    window = max(int(rep_frames / 3), 1)
    key = np.sort(np.asarray(key_peaks, dtype=np.int64))
    strict = find_repetition_peaks(height, rep_frames)
    sure = _near(strict, key, window)
    # with no peak confirmed (a classifier trained on another recorder may place every end of
    # range off the axis's peaks), the axis's own peaks set the height a repetition reaches
    confirmed = strict[sure] if sure.any() else strict
    typical = float(np.median(height[confirmed])) if confirmed.size else 0.0
    kept = strict[sure | (height[strict] >= UNCONFIRMED_HEIGHT * typical)]
    lonely = key[~_near(key, kept, window)]
    if kept.size < 2 or lonely.size == 0:
        return kept.astype(np.int64)
    typical = float(np.median(height[kept]))
    moving = [f for f in lonely.tolist() if moves_near(height, f, window, typical)]
    lonely = np.array(moving, dtype=np.int64)
    spacing = float(np.median(np.diff(kept)))
    bounds = np.concatenate([[-np.inf], kept, [np.inf]])
    extra = []
    for frame in lonely.tolist():
        right = int(np.searchsorted(kept, frame))
        before, after = frame - bounds[right], bounds[right + 1] - frame
        if before + after > GAP_FACTOR * spacing and min(before, after) >= 0.5 * spacing:
            extra.append(frame)
    return np.unique(np.concatenate([kept, extra])).astype(np.int64)


def moves_near(height: FloatArray, frame: int, window: int, typical: float) -> bool:
    """Whether ``height`` rises within ``window`` frames of ``frame`` by half `MIN_PROMINENCE`
    and by `MISSED_SHARE` of ``typical`` (the recording's repetitions' height)."""
    near = height[max(frame - window, 0) : frame + window + 1]
    if near.size == 0:
        return False
    rise = float(near.max() - near.min())
    return rise >= 0.5 * MIN_PROMINENCE and rise >= MISSED_SHARE * typical


def _near(frames: IntArray, others: IntArray, window: int) -> npt.NDArray[np.bool_]:
    """Which ``frames`` have one of ``others`` within ``window`` frames."""
    if frames.size == 0 or others.size == 0:
        return np.zeros(frames.size, dtype=bool)
    return np.min(np.abs(frames[:, None] - others[None, :]), axis=1) <= window


def segment(progress: FloatArray, rep_frames: float) -> Segments:
    """Cut a progress signal into repetitions (see the module docstring)."""
    if progress.size == 0:
        return _no_segments()
    height = rest_height(progress, rep_frames)
    return segments_at(height, find_repetition_peaks(height, rep_frames), rep_frames)


def rest_height(progress: FloatArray, rep_frames: float) -> FloatArray:
    """The cleaned progress signal above the recording's rest level (tutor units)."""
    smooth = clean_progress(np.asarray(progress, dtype=np.float64), rep_frames)
    return smooth - float(np.percentile(smooth, REST_PERCENTILE))


def segments_at(height: FloatArray, peaks: IntArray, rep_frames: float) -> Segments:
    """Repetitions around given end-of-range frames (increasing): each starts in the middle of
    the rest before its peak (see the module docstring)."""
    peaks = np.asarray(peaks, dtype=np.int64)
    if peaks.size == 0:
        return _no_segments()
    cuts = [middle_of_rest(height, int(a), int(b)) for a, b in itertools.pairwise(peaks)]
    lead = half_rest(height, cuts, peaks, rep_frames)
    first = min(max(0, leaves_rest(height, int(peaks[0])) - lead), int(peaks[0]) - 1)
    last = back_at_rest(height, int(peaks[-1])) + lead
    last = max(min(height.size - 1, last), int(peaks[-1]) + 1)
    starts = np.array([first, *cuts], dtype=np.int64)
    ends = np.array([*(c - 1 for c in cuts), last], dtype=np.int64)
    return Segments(starts, np.maximum(ends, starts), peaks)


def half_rest(signal: FloatArray, cuts: list[int], peaks: IntArray, rep_frames: float) -> int:
    """The recording's typical half rest: median frames from a cut to the next movement onset
    (a sixth of the tutor's repetition when there is no cut to measure)."""
    if not cuts:
        return int(rep_frames / 6)
    gaps = [
        leaves_rest(signal[cut:], int(peak) - cut)
        for cut, peak in zip(cuts, peaks[1:], strict=True)
    ]
    return int(np.median(gaps))


def _no_segments() -> Segments:
    empty = np.zeros(0, dtype=np.int64)
    return Segments(empty, empty, empty)


def middle_of_rest(signal: FloatArray, peak_a: int, peak_b: int) -> int:
    """The frame `REST_SPLIT` of the way from the end of the return from ``peak_a`` to the start
    of the movement to ``peak_b``: the first and last frames between them that are within
    `REST_FRACTION` of the lower peak's height above the trough."""
    between = signal[peak_a : peak_b + 1]
    low = float(between.min())
    threshold = low + REST_FRACTION * (min(signal[peak_a], signal[peak_b]) - low)
    resting = np.flatnonzero(between <= threshold)
    return peak_a + round(resting[0] + REST_SPLIT * (resting[-1] - resting[0]))


def leaves_rest(signal: FloatArray, peak: int) -> int:
    """The last frame before ``peak`` within `REST_FRACTION` of its rise (the movement onset)."""
    before = signal[: peak + 1]
    low = float(before.min())
    resting = np.flatnonzero(before <= low + REST_FRACTION * (signal[peak] - low))
    return int(resting[-1])


def back_at_rest(signal: FloatArray, peak: int) -> int:
    """The first frame after ``peak`` within `REST_FRACTION` of its fall (the return's end)."""
    after = signal[peak:]
    low = float(after.min())
    resting = np.flatnonzero(after <= low + REST_FRACTION * (signal[peak] - low))
    return peak + int(resting[0])
