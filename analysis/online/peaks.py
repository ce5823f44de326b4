"""The repetition counter's compiled searches (`analysis.online.counting`): scipy's
``find_peaks`` with a distance and a least prominence, and numpy's default percentile, each the
library's answer to the last bit (`tests/live/test_compiled_live.py`) for a fraction of its
call's cost on a live session's short signals."""

from __future__ import annotations

import math

import numba as nb
import numpy as np
import numpy.typing as npt
from scipy.signal import find_peaks

from analysis.landmarks.segmentation import MIN_PROMINENCE

FloatArray = npt.NDArray[np.float64]


def percentile(values: FloatArray, q: float) -> float:
    """``np.percentile(values, q)`` (numpy's default, linear method) for a non-empty 1-D array,
    the same value to the last bit: the two neighbours of the virtual index by one partition
    and numpy's interpolation formula, without np.percentile's general machinery (ten times
    the work for the cleaned signal of a live session)."""
    n = values.size
    if n == 1:
        return float(values[0])
    virtual = (n - 1) * (q / 100)
    below = math.floor(virtual)
    if below >= n - 1:
        return float(np.max(values))
    part = np.partition(values, (below, below + 1))
    a, b = float(part[below]), float(part[below + 1])
    gamma, diff = virtual - below, b - a
    return b - diff * (1 - gamma) if gamma >= 0.5 else a + diff * gamma


def prominent_peaks(
    window: FloatArray, left: int, right: int, floor: float, distance: int
) -> tuple[list[int], list[float]]:
    """``find_peaks(padded, distance=distance, prominence=MIN_PROMINENCE)``'s peaks and their
    prominences, ``padded`` the window with ``left`` and ``right`` values of ``floor`` either
    side: scipy's steps compiled into one call (`_peaks_kernel`). Peaks of equal height make
    the distance rule's order depend on the sort's tie-breaking: scipy answers those."""
    peaks, prominences, ties = _peaks_kernel(
        np.ascontiguousarray(window), left, right, floor, distance, MIN_PROMINENCE
    )
    if ties:
        padded = np.pad(window, (left, right), mode="constant", constant_values=floor)
        found, props = find_peaks(padded, distance=distance, prominence=MIN_PROMINENCE)
        return found.tolist(), props["prominences"].tolist()
    return peaks.tolist(), prominences.tolist()


@nb.njit(cache=True, nogil=True)
def _peaks_kernel(  # noqa: PLR0917 - numba functions take positional arguments only
    window: FloatArray, left: int, right: int, floor: float, distance: int, least: float
) -> tuple[npt.NDArray[np.int64], FloatArray, bool]:
    """scipy.signal.find_peaks (1.x: `_local_maxima_1d`, `_select_by_peak_distance`,
    `_peak_prominences` with no window, then prominence >= ``least``) on the padded window;
    True last when two candidate peaks are equally high (then the caller asks scipy)."""
    x = np.full(left + window.size + right, floor)
    x[left : left + window.size] = window
    peaks = _local_maxima(x)
    heights = x[peaks]
    order = np.argsort(heights)
    for r in range(1, peaks.size):
        if heights[order[r]] == heights[order[r - 1]]:
            return peaks, heights, True
    peaks = peaks[_far_enough(peaks, order, distance)]
    prominences = np.empty(peaks.size)
    for r in range(peaks.size):
        prominences[r] = _prominence(x, peaks[r])
    chosen = prominences >= least
    return peaks[chosen], prominences[chosen], False


@nb.njit(cache=True, nogil=True)
def _local_maxima(x: FloatArray) -> npt.NDArray[np.int64]:
    """Indices of x's local maxima, a plateau's middle (rounded down), as scipy finds them."""
    n = x.size
    mids = np.empty(n // 2 + 1, np.int64)
    m, i = 0, 1
    while i < n - 1:
        if x[i - 1] < x[i]:
            ahead = i + 1
            while ahead < n - 1 and x[ahead] == x[i]:
                ahead += 1
            if x[ahead] < x[i]:
                mids[m] = (i + ahead - 1) // 2
                m += 1
                i = ahead
        i += 1
    return mids[:m]


@nb.njit(cache=True, nogil=True)
def _far_enough(
    peaks: npt.NDArray[np.int64], order: npt.NDArray[np.int64], distance: int
) -> npt.NDArray[np.bool_]:
    """scipy's distance rule: from the highest peak down, drop the lower ones closer than
    ``distance``; ``order``: the peaks by height, lowest first."""
    m = peaks.size
    keep = np.ones(m, np.bool_)
    for r in range(m - 1, -1, -1):
        j = order[r]
        if not keep[j]:
            continue
        k = j - 1
        while k >= 0 and peaks[j] - peaks[k] < distance:
            keep[k] = False
            k -= 1
        k = j + 1
        while k < m and peaks[k] - peaks[j] < distance:
            keep[k] = False
            k += 1
    return keep


@nb.njit(cache=True, nogil=True)
def _prominence(x: FloatArray, p: int) -> float:
    """How far x[p] stands above the higher of the lowest points either side before x rises
    above it (scipy's prominence with no window)."""
    left_min = right_min = x[p]
    i = p
    while i >= 0 and x[i] <= x[p]:
        left_min = min(left_min, x[i])
        i -= 1
    i = p
    while i < x.size and x[i] <= x[p]:
        right_min = min(right_min, x[i])
        i += 1
    return x[p] - max(left_min, right_min)
