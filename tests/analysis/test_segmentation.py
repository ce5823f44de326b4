"""Repetition boundaries on the progress signal (analysis/landmarks/segmentation.py)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from analysis.landmarks.segmentation import fit_axis, middle_of_rest, segment

REP = 60  # frames of one tutor repetition, rest included
FloatArray = npt.NDArray[np.float64]


def _hump(rise: int, hold: int, height: float = 1.0) -> FloatArray:
    """Rise from 0 to ``height`` and back (raised cosine), holding the top for ``hold`` frames."""
    up = height * 0.5 * (1 - np.cos(np.linspace(0, np.pi, rise)))
    return np.concatenate([up, np.full(hold, height), up[::-1]])


def _session(humps: list[FloatArray], rests: list[int]) -> tuple[FloatArray, list[int]]:
    """Rest, hump, rest, hump, …; true starts: 0, then the middle of each rest between humps."""
    parts: list[FloatArray] = [np.zeros(rests[0])]
    starts = [0]
    for k, hump in enumerate(humps):
        parts.append(hump)
        rest = rests[k + 1]
        if k + 1 < len(humps):
            starts.append(sum(p.size for p in parts) + rest // 2)
        parts.append(np.zeros(rest))
    return np.concatenate(parts), starts


def test_ten_repetitions_start_in_the_middle_of_each_rest() -> None:
    signal, starts = _session([_hump(20, 5)] * 10, [8] + [16] * 10)
    found = segment(signal, REP)
    assert found.starts.size == 10
    # cut 45 % of the way through each 16-frame rest (REST_SPLIT), one frame before its middle
    assert np.abs(found.starts[1:] - np.array(starts[1:])).max() <= 2
    assert 0 <= found.starts[0] < 8  # within the rest before the first movement
    assert np.all(found.starts < found.peaks) and np.all(found.peaks <= found.ends)
    assert np.all(found.ends[:-1] == found.starts[1:] - 1)


def test_start_is_not_the_noisy_lowest_point_of_a_long_rest() -> None:
    signal, starts = _session([_hump(20, 5)] * 3, [8, 40, 40, 8])
    rng = np.random.default_rng(3)
    signal = signal + rng.normal(0.0, 0.01, signal.size)
    signal[starts[1] - 15] -= 0.05  # the lowest frame sits far from the middle of the rest
    found = segment(signal, REP)
    assert np.abs(found.starts[1:] - np.array(starts[1:])).max() <= 3


def test_two_humps_of_one_repetition_count_once() -> None:
    # sit to stand: up, a half dip without sitting down, up again, then back to rest
    up = _hump(15, 0)[:15]
    dip = 1.0 - _hump(10, 2, 0.35)
    top = np.ones(8)
    double = np.concatenate([up, top, dip, top * 1.05, 1.05 * up[::-1]])
    signal, _ = _session([_hump(15, 20), double, _hump(15, 20)], [8, 16, 16, 8])
    assert segment(signal, REP).starts.size == 3


def test_sensor_spikes_in_a_rest_are_not_repetitions() -> None:
    signal, starts = _session([_hump(20, 5)] * 4, [8, 30, 30, 30, 8])
    for frame in (starts[1] + 3, starts[2] - 4, starts[3]):
        signal[frame] = 0.8  # one-frame jumps of a depth sensor
    assert segment(signal, REP).starts.size == 4


def test_a_small_range_still_counts_and_jitter_does_not() -> None:
    small = [_hump(20, 5, 0.25)] * 5
    signal, _ = _session(small, [8] + [16] * 5)
    assert segment(signal, REP).starts.size == 5
    jitter = 0.04 * np.sin(np.linspace(0, 40 * np.pi, 600))
    assert segment(jitter, REP).starts.size == 0


def test_a_repetition_cut_off_by_the_end_counts_with_distinct_frames() -> None:
    signal, _ = _session([_hump(20, 5)] * 3, [8, 16, 16, 0])
    signal = np.concatenate([signal, _hump(20, 0)[:20]])  # stops at the top of a fourth rise
    found = segment(signal, REP)
    assert found.starts.size == 4
    assert found.peaks[-1] < found.ends[-1] <= signal.size - 1
    assert found.starts[0] < found.peaks[0]


def test_nothing_to_cut() -> None:
    assert segment(np.zeros(0), REP).starts.size == 0
    assert segment(np.zeros(200), REP).starts.size == 0


def test_middle_of_rest_is_between_return_and_onset() -> None:
    signal = np.concatenate([_hump(10, 0), np.zeros(20), _hump(10, 0)])
    # peaks at frames 9 and 49, rest (zeros) on frames 20..39
    middle = middle_of_rest(signal, 9, 49)
    assert 27 <= middle <= 32


def test_progress_axis_puts_the_tutor_between_zero_and_one() -> None:
    rng = np.random.default_rng(0)
    direction = rng.normal(size=6)
    t = np.concatenate([_hump(20, 5)] * 3)
    features = np.outer(t, direction) + rng.normal(0.0, 0.01, (t.size, 6)) + 3.0
    starts = np.array([0, 45, 90])
    peaks = starts + 22
    axis = fit_axis(features, starts, peaks)
    progress = axis.progress(features)
    assert abs(progress[starts].mean()) < 0.05
    assert abs(progress[peaks].mean() - 1.0) < 0.05
    assert axis.rep_frames == 45.0
