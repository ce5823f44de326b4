"""Frame-wise features (thesis 004, 5.4.2, eqs 5.14–5.18) on small hand-checked series."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from analysis.landmarks.features import extrema, feature_names, frame_features, nearest_extrema

# frames:            0  1  2  3  4  5  6
SERIES = np.array([0.0, 1, 3, 2, 2, 5, 4])
# extrema (eq 5.14, corrected): 2 is a peak (1 < 3 ≥ 2), 3 a valley (3 > 2 ≤ 2), 5 a peak.


def test_extrema_are_local_peaks_and_valleys_not_the_ends():
    assert np.flatnonzero(extrema(SERIES)).tolist() == [2, 3, 5]


def test_rising_frames_are_not_extrema_as_the_printed_eq_5_14_would_say():
    ramp = np.arange(6.0)
    assert not extrema(ramp).any()


def test_a_flat_top_gives_one_extremum_at_its_first_frame():
    assert np.flatnonzero(extrema(np.array([0.0, 2, 2, 2, 0]))).tolist() == [1]


def test_ends_option_makes_the_first_and_last_frame_extrema():
    assert np.flatnonzero(extrema(SERIES, ends=True)).tolist() == [0, 2, 3, 5, 6]


def test_nearest_extrema_left_and_right_include_the_frame_itself():
    left, right = nearest_extrema(extrema(SERIES)[:, None])
    assert left[:, 0].tolist() == [-1, -1, 2, 3, 3, 5, 5]  # eq 5.15
    assert right[:, 0].tolist() == [2, 2, 2, 3, 5, 5, -1]  # eq 5.16


def test_features_of_eq_5_17_by_hand():
    f = frame_features(SERIES)
    assert f.shape == (7, 4)
    # frame 4 (value 2): left extremum 3 (value 2), right extremum 5 (value 5)
    np.testing.assert_allclose(f[4], [1, 1, 0, -3])
    # frame 1 (value 1): no extremum on the left -> unknown; right extremum 2 (value 3)
    assert np.isnan(f[1, 0]) and np.isnan(f[1, 2])
    np.testing.assert_allclose(f[1, [1, 3]], [1, -2])
    # frame 6: nothing on the right
    assert np.isnan(f[6, 1]) and np.isnan(f[6, 3])
    np.testing.assert_allclose(f[6, [0, 2]], [1, -1])


def test_features_at_an_extremum_are_zero_on_both_sides():
    np.testing.assert_allclose(frame_features(SERIES)[5], [0, 0, 0, 0])


def test_strict_neighbours_tell_a_peak_from_a_valley():
    f = frame_features(SERIES, strict=True)
    # frame 2 (peak 3): previous extremum none (unknown), next one frame 3 (value 2)
    assert np.isnan(f[2, 0]) and f[2, 1] == 1 and f[2, 3] == 1
    # frame 3 (valley 2): neighbours 2 (value 3) and 5 (value 5) → negative heights
    np.testing.assert_allclose(f[3], [1, 2, -1, -3])


def test_with_ends_nothing_is_unknown():
    f = frame_features(SERIES, ends=True)
    assert not np.isnan(f).any()
    np.testing.assert_allclose(f[1], [1, 1, 1, -2])


def test_columns_are_grouped_by_feature_then_series():
    sig = np.column_stack([SERIES, -SERIES])
    f = frame_features(sig)
    assert f.shape == (7, 8)
    assert feature_names(2)[:3] == ["x_width_left[0]", "x_width_left[1]", "x_width_right[0]"]
    np.testing.assert_allclose(f[4, [2, 3, 4, 5]], [1, 1, 0, 0])
    np.testing.assert_allclose(f[4, [6, 7]], [-3, 3])  # heights to the right change sign


def _reference(series: np.ndarray) -> np.ndarray:
    """Loop implementation of eqs 5.14–5.17 for one series."""
    n = len(series)
    peaks = [
        t
        for t in range(1, n - 1)
        if (series[t - 1] < series[t] >= series[t + 1])
        or (series[t - 1] > series[t] <= series[t + 1])
    ]
    out = np.full((n, 4), np.nan)
    for t in range(n):
        left = [p for p in peaks if p <= t]
        right = [p for p in peaks if p >= t]
        if left:
            out[t, 0], out[t, 2] = t - left[-1], series[t] - series[left[-1]]
        if right:
            out[t, 1], out[t, 3] = right[0] - t, series[t] - series[right[0]]
    return out


@settings(max_examples=60, derandomize=True, deadline=None)
@given(st.lists(st.integers(-3, 3), min_size=1, max_size=25))
def test_vectorised_features_equal_the_loop_reference(values):
    series = np.array(values, dtype=float)
    np.testing.assert_allclose(frame_features(series), _reference(series), equal_nan=True)
