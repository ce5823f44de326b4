"""Frame-wise features of a motion signature (paper 004, section 5.4.2, eqs 5.14–5.18).

For every frame t and signature series s, the features describe the curve around t by its nearest
local extrema: the distance in frames to the closest extremum on the left and on the right
(X_WIDTH_LEFT/RIGHT) and the height of s(t) above each of them (Y_HEIGHT_LEFT/RIGHT). Frames with no
extremum on one side (near the ends of the recording) get *unknown* values there, encoded as NaN.

Erratum: eq 5.14 as printed (s(t−1) < s(t) ≤ s(t+1) or s(t−1) ≤ s(t) < s(t+1)) selects rising
frames, not extrema; the text and Figure 5.5 mean local maxima and minima, implemented here as
s(t−1) < s(t) ≥ s(t+1) or s(t−1) > s(t) ≤ s(t+1) (one non-strict side, so a flat top of equal values
yields one extremum at its first frame, not none). The first and last frames have no neighbour on
one side and are never extrema.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

FEATURE_NAMES = ("x_width_left", "x_width_right", "y_height_left", "y_height_right")


def extrema(series: FloatArray, ends: bool = False) -> BoolArray:
    """Eq 5.14 (corrected, see module note): local extremum frames of each column.

    series: (F,) or (F, D). ends: also count the first and last frame as extrema (an option beside
    the thesis's unknown-value rule). Returns a boolean mask of the same shape.
    """
    s = np.asarray(series, dtype=np.float64)
    mask = np.zeros(s.shape, dtype=bool)
    if s.shape[0] < 3:
        return mask
    left, mid, right = s[:-2], s[1:-1], s[2:]
    peak = (left < mid) & (mid >= right)
    valley = (left > mid) & (mid <= right)
    mask[1:-1] = peak | valley
    if ends:
        mask[0] = mask[-1] = True
    return mask


def nearest_extrema(mask: BoolArray, strict: bool = False) -> tuple[IntArray, IntArray]:
    """Eqs 5.15–5.16: per frame, the closest extremum at or before it and at or after it.

    mask: (F, D) from `extrema`. strict: strictly before and strictly after (ours, see
    `frame_features`). Returns two (F, D) int arrays of frame indices, −1 where there is no
    extremum on that side.
    """
    n = mask.shape[0]
    frames = np.arange(n, dtype=np.int64).reshape((n,) + (1,) * (mask.ndim - 1))
    left = np.maximum.accumulate(np.where(mask, frames, -1), axis=0)
    right_rev = np.minimum.accumulate(np.where(mask, frames, n)[::-1], axis=0)[::-1]
    right = np.where(right_rev >= n, -1, right_rev)
    if strict:
        left = np.vstack([np.full_like(left[:1], -1), left[:-1]])
        right = np.vstack([right[1:], np.full_like(right[:1], -1)])
    return left, right


def frame_features(signature: FloatArray, ends: bool = False, strict: bool = False) -> FloatArray:
    """Eqs 5.17–5.18: the four frame-wise features of every signature series at every frame.

    signature: (F, D) (a 1-D series is treated as D = 1). Returns (F, 4·D) float, columns grouped
    by feature then series: [X_WIDTH_LEFT (D), X_WIDTH_RIGHT (D), Y_HEIGHT_LEFT (D),
    Y_HEIGHT_RIGHT (D)]; widths in frames, heights in signature units; NaN = unknown. With
    ``ends`` the recording's first and last frames count as extrema, so nothing is unknown.

    As printed, a frame at an extremum is its own nearest extremum on both sides, so all four
    features are 0 there, at a peak as at a valley: ``strict`` (ours) uses the nearest extrema
    strictly before and after the frame instead, which tells the two apart.
    """
    sig = np.asarray(signature, dtype=np.float64)
    if sig.ndim == 1:
        sig = sig[:, None]
    left, right = nearest_extrema(extrema(sig, ends), strict)
    t = np.arange(sig.shape[0], dtype=np.float64)[:, None]
    has_left, has_right = left >= 0, right >= 0
    left_values = np.take_along_axis(sig, np.maximum(left, 0), axis=0)
    right_values = np.take_along_axis(sig, np.maximum(right, 0), axis=0)
    return np.hstack(
        [
            np.where(has_left, t - left, np.nan),
            np.where(has_right, right - t, np.nan),
            np.where(has_left, sig - left_values, np.nan),
            np.where(has_right, sig - right_values, np.nan),
        ]
    )


def feature_names(n_series: int) -> list[str]:
    """Column names of `frame_features` for a signature of ``n_series`` series."""
    return [f"{name}[{k}]" for name in FEATURE_NAMES for k in range(n_series)]
