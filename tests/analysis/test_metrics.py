"""Alignment and similarity metrics."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.dtw import align
from analysis.dtw.metrics import (
    displacement_vectors,
    kendall_tau_score,
    mapping_deviation,
    offline_mapping,
    pearson_score,
    pose_distance,
    segment_agreement,
    segment_labels,
)
from analysis.kinematics import quaternions as quat


def swinging_joints(n: int, phase: float = 0.0) -> np.ndarray:
    """(n, 2, 4): two joints rotating back and forth about x and z."""
    t = np.linspace(0, 2 * np.pi, n) + phase
    return np.stack([quat.from_axis_angle("x", 0.6 * np.sin(t)),
                     quat.from_axis_angle("z", 0.4 * np.cos(t))], axis=1)  # fmt: skip


def test_displacement_vector_of_identity_is_up() -> None:
    np.testing.assert_allclose(displacement_vectors(quat.identity((3,))), [[0, 1, 0]] * 3)
    v = displacement_vectors(quat.from_axis_angle("z", np.pi / 2))
    np.testing.assert_allclose(v, [-1.0, 0.0, 0.0], atol=1e-12)


def test_kendall_tau_perfect_and_misaligned() -> None:
    a = swinging_joints(100)
    assert kendall_tau_score(a, a) == pytest.approx(1.0)
    late = swinging_joints(100, phase=1.5)
    score = kendall_tau_score(a, late)
    assert score < 0.6
    # DTW re-aligns the shifted copy: the aligned score goes back up
    flat = lambda q: q.reshape(len(q), -1)  # noqa: E731
    path = align(flat(late), flat(a), None).path
    assert kendall_tau_score(late, a, path) > score


def test_constant_curves_count_as_agreement_only_when_both_constant() -> None:
    a = swinging_joints(50)
    b = a.copy()
    b[:, 1] = quat.identity((50,))  # joint 1 frozen in one motion only
    frozen_both = a.copy()
    frozen_both[:, 1] = quat.identity((50,))
    assert kendall_tau_score(frozen_both, frozen_both) == pytest.approx(1.0)
    assert kendall_tau_score(a, b) < kendall_tau_score(a, a)


def test_pearson_score() -> None:
    x = np.sin(np.linspace(0, 6, 60))[:, None]
    assert pearson_score(x, 3 * x + 1) == pytest.approx(1.0)
    assert pearson_score(x, -x) == pytest.approx(-1.0)
    with pytest.raises(ValueError, match="equal lengths"):
        pearson_score(x, x[:10])


def test_segment_labels_and_agreement() -> None:
    labels = segment_labels(10, [0, 3, 7])
    np.testing.assert_array_equal(labels, [0, 0, 0, 1, 1, 1, 1, 2, 2, 2])
    path = np.array([[0, 0], [1, 0], [2, 1], [3, 1], [4, 2]])
    ref = np.array([0, 0, 1])
    assert segment_agreement(path, labels, ref) == pytest.approx(4 / 5)


def test_mapping_deviation_against_offline_path() -> None:
    path = np.array([[0, 0], [1, 1], [1, 2], [2, 3], [3, 3]])
    np.testing.assert_allclose(offline_mapping(path, 4), [0, 1.5, 3, 3])
    dev = mapping_deviation([0, 1, 3, 5], path)
    assert dev.median == pytest.approx(0.25)
    assert dev.max == 2.0 and dev.mean == pytest.approx(2.5 / 4)
    assert dev.bias == pytest.approx((0 + 0.5 + 0 - 2) / 16)
    assert dev.max_norm == pytest.approx(2 / 4)


def test_pose_distance_angular_and_positional() -> None:
    a = swinging_joints(20)
    assert pose_distance(a, a) == pytest.approx(0.0, abs=1e-12)
    turned = quat.multiply(quat.from_axis_angle("y", np.full((20, 2), 0.5)), a)
    # every joint 0.5 rad away: (2/pi) * 0.25 per joint, two joints
    assert pose_distance(a, turned) == pytest.approx(2 * (2 / np.pi) * 0.25, rel=1e-9)
    assert pose_distance(a, turned, weights=[1.0, 0.0]) == pytest.approx((2 / np.pi) * 0.25)
    p = np.zeros((5, 3, 3))
    q = p + np.array([0.0, 3.0, 4.0])
    assert pose_distance(p, q, kind="positional") == pytest.approx(15.0)
    with pytest.raises(ValueError):
        pose_distance(p, q, kind="velocity")


def test_vectorised_kendall_tau_b_matches_scipy_with_ties() -> None:
    from scipy import stats

    from analysis.dtw.metrics import kendall_tau_b

    rng = np.random.default_rng(3)
    a = rng.normal(size=(150, 6))
    b = np.round(a + rng.normal(size=a.shape), 1)  # rounding makes ties
    a[::4, 1] = a[0, 1]
    expected = [stats.kendalltau(a[:, c], b[:, c]).statistic for c in range(6)]
    np.testing.assert_allclose(kendall_tau_b(a, b, block=16), expected, atol=1e-12)
