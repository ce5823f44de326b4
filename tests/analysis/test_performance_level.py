"""Γ (eq 7.14): exponential smoothing of normalised assessment levels."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analysis.assessment.performance_level import session_value, update_levels

levels_lists = st.lists(st.integers(1, 4), min_size=1, max_size=12)


def test_first_session_is_the_session_value():
    gamma = update_levels(None, {"Knee": [1, 1, 2, 4], "Hip": [1]})
    assert gamma == {"Knee": pytest.approx((1 + 1 + 2 / 3 + 0) / 4), "Hip": 1.0}


def test_level_one_is_one_and_the_worst_level_is_zero():
    assert session_value([1, 1, 1]) == 1.0
    assert session_value([4, 4]) == 0.0
    assert session_value([3], n_levels=3) == 0.0
    assert session_value([0, 0]) is None  # nothing assessed


def test_smoothing_weights_the_new_session():
    gamma = update_levels({"Knee": 0.5}, {"Knee": [1, 1]}, smoothing=0.3)
    assert gamma["Knee"] == pytest.approx(0.7 * 0.5 + 0.3 * 1.0)


def test_joints_not_assessed_keep_their_level():
    gamma = update_levels({"Knee": 0.4, "Hip": 0.9}, {"Knee": [4], "Elbow": [0]})
    assert gamma["Hip"] == 0.9 and "Elbow" not in gamma
    assert gamma["Knee"] == pytest.approx(0.7 * 0.4)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match=r"1\.\.4"):
        update_levels(None, {"Knee": [5]})
    with pytest.raises(ValueError, match="smoothing"):
        update_levels(None, {"Knee": [1]}, smoothing=0.0)


@settings(max_examples=80, derandomize=True, deadline=None)
@given(st.floats(0.0, 1.0), st.lists(levels_lists, min_size=1, max_size=6), st.floats(0.05, 1.0))
def test_gamma_stays_in_the_unit_interval(start, sessions, smoothing):
    gamma = {"J": start}
    for levels in sessions:
        gamma = update_levels(gamma, {"J": levels}, smoothing=smoothing)
        assert 0.0 <= gamma["J"] <= 1.0


@settings(max_examples=80, derandomize=True, deadline=None)
@given(st.floats(0.0, 1.0), levels_lists, st.integers(0, 11))
def test_better_levels_never_lower_gamma(start, levels, which):
    which %= len(levels)
    better = list(levels)
    better[which] = max(1, better[which] - 1)
    worse_gamma = update_levels({"J": start}, {"J": levels})["J"]
    better_gamma = update_levels({"J": start}, {"J": better})["J"]
    assert better_gamma >= worse_gamma
    # and a higher previous γ never gives a lower new γ
    assert update_levels({"J": min(1.0, start + 0.1)}, {"J": levels})["J"] >= worse_gamma


def test_constant_sessions_converge_geometrically():
    gamma, target, alpha = {"J": 0.0}, session_value([1, 2]), 0.3
    assert target is not None
    for n in range(1, 21):
        gamma = update_levels(gamma, {"J": [1, 2]}, smoothing=alpha)
        assert gamma["J"] == pytest.approx(target * (1 - (1 - alpha) ** n))
    assert math.isclose(gamma["J"], target, abs_tol=1e-3)
