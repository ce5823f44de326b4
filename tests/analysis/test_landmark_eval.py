"""Compromise intervals and landmark confusion counts (thesis 004, 5.6.1, eqs 5.34–5.36)."""

import numpy as np
import pytest

from analysis.landmarks.evaluation import (
    Confusion,
    compromise_intervals,
    confusion,
    evaluate,
    match,
    summed,
)

# A 1-D motion: rest (0) → end of range (10) → rest, landmarks at 0 (type 1), 5 (2), 10 (1).
M = np.array([0.0, 0, 1, 4, 8, 10, 10, 9, 5, 1, 0])[:, None]
GT_FRAMES = np.array([0, 5, 10])
GT_TYPES = np.array([1, 2, 1])


def test_compromise_intervals_by_hand():
    # landmark 5: both neighbours are 10 away, so frames within 1.5 of M[5] = 10 count: 5..7.
    # landmark 0: its left neighbour is frame 0 itself; to the right, within 1.5 of 0: 0..2.
    # landmark 10: left within 1.5 of 0 back to 9; right neighbour is the last frame itself.
    intervals = compromise_intervals(M, GT_FRAMES, 0.15)
    assert intervals.tolist() == [[0, 2], [5, 7], [9, 10]]


def test_interval_stops_at_the_first_frame_beyond_the_threshold():
    # A dip back inside the threshold after leaving it does not extend the interval.
    data = np.array([0.0, 0.5, 3.0, 0.5, 10.0])[:, None]
    assert compromise_intervals(data, [0], 0.15).tolist() == [[0, 1]]


def test_interval_never_crosses_the_neighbouring_landmark():
    flat = np.zeros((9, 1))  # every pose within any threshold
    assert compromise_intervals(flat, [2, 6], 1.0).tolist() == [[0, 6], [2, 8]]


def test_distances_are_taxicab_over_all_columns():
    data = np.array([[0.0, 0.0], [0.5, 0.6], [10.0, 0.0]])
    # threshold = |(0,0) − (10,0)|₁ · 0.1 = 1; frame 1 is 1.1 away in L1 (0.78 in L2)
    assert compromise_intervals(data, [0, 2], 0.1)[0].tolist() == [0, 0]
    assert compromise_intervals(data, [0, 2], 0.12)[0].tolist() == [0, 1]


def test_confusion_counts_of_eq_5_35():
    intervals = compromise_intervals(M, GT_FRAMES, 0.15)
    frames = np.array([1, 4, 6, 7, 10])
    types = np.array([1, 1, 2, 2, 2])
    # 1 matches the first start, 6 the end of range; 7 is a second match of the same landmark
    # (counted as a false positive, 5.6.2); 4 is in no type-1 interval; 10 has the wrong type.
    c = confusion(frames, types, GT_TYPES, intervals, n_frames=len(M))
    assert c == Confusion(tp=2, fp=3, fn=1, tn=11 - 6)
    assert c.precision == pytest.approx(2 / 5)
    assert c.accuracy == pytest.approx((2 + 5) / 11)
    assert c.strict_accuracy == pytest.approx(2 / 6)


def test_perfect_detection():
    c = evaluate(GT_FRAMES, GT_TYPES, GT_FRAMES, GT_TYPES, M, delta=0.15)
    assert (c.tp, c.fp, c.fn) == (3, 0, 0)
    assert c.precision == c.accuracy == c.strict_accuracy == 1.0


def test_nothing_detected():
    c = evaluate([], [], GT_FRAMES, GT_TYPES, M, delta=0.15)
    assert (c.tp, c.fp, c.fn) == (0, 0, 3)
    assert c.precision == 0.0
    assert c.strict_accuracy == 0.0


def test_matching_is_one_to_one_and_maximal():
    intervals = np.array([[0, 10], [5, 6]])
    # Taking the wide interval first would give it frame 5 and leave the narrow one unmatched.
    owner = match([5, 8], [1, 1], [1, 1], intervals)
    assert sorted(owner.tolist()) == [0, 1]
    assert owner.tolist() == [1, 0]


def test_summed_adds_counts():
    total = summed([Confusion(1, 2, 3, 4), Confusion(10, 20, 30, 40)])
    assert total == Confusion(11, 22, 33, 44)
