"""CMA-ES joint weights (paper 000): the informative joint gains weight and the error drops."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.dtw import DTWOptions, align, cost_matrix
from analysis.dtw.joint_weights import JointWeightOptimizer, aligned_pairs, alignment_error
from analysis.online import OpenEndAligner


def performance(rng: np.random.Generator, n: int, noise: float) -> tuple[np.ndarray, np.ndarray]:
    """Joint 0 moves through 4 phases (labels); joints 1 and 2 only carry sensor noise."""
    u = np.linspace(0.0, 1.0, n) ** rng.uniform(0.8, 1.25)  # each take has its own timing
    labels = np.minimum((u * 4).astype(int), 3)
    move = np.sin(2 * np.pi * u) + u
    frames = np.stack([move, noise * rng.standard_normal(n), noise * rng.standard_normal(n)], 1)
    return frames, labels


def test_aligned_pairs_online_are_the_streaming_answers() -> None:
    rng = np.random.default_rng(0)
    x, y = rng.standard_normal((12, 2)), rng.standard_normal((10, 2))
    opt = DTWOptions(path_length_weighting=True)
    pairs = aligned_pairs(cost_matrix(x, y), opt, "online")
    oa = OpenEndAligner(y, opt)
    np.testing.assert_array_equal(pairs[:, 1], [oa.push(f) for f in x])
    path = aligned_pairs(cost_matrix(x, y), opt, "path")
    np.testing.assert_array_equal(
        path, align(x, y, DTWOptions(path_length_weighting=True, open_end=True)).path
    )


def test_alignment_error_is_eq_5() -> None:
    pairs = np.array([[0, 0], [1, 1], [2, 1], [3, 2]])
    assert alignment_error(pairs, [0, 0, 1, 1], [0, 1, 1]) == pytest.approx(1 / 4)


def test_cma_es_downweights_noise_and_reduces_the_error() -> None:
    rng = np.random.default_rng(1)
    ref, ref_labels = performance(rng, 80, noise=0.0)
    takes = [performance(rng, int(rng.integers(70, 100)), noise=1.0) for _ in range(3)]
    opt = JointWeightOptimizer(
        options=DTWOptions(cost="euclidean", path_length_weighting=True), iterations=12, seed=3
    )
    opt.fit(ref, ref_labels, [t[0] for t in takes], [t[1] for t in takes])
    assert opt.error_ < opt.initial_error_
    assert opt.weights_[0] > max(opt.weights_[1], opt.weights_[2])
    assert opt.weights_.mean() == pytest.approx(1.0)
    assert len(opt.history_) == 12 and opt.history_[-1] == opt.error_
    # the learned weights also help a take it has not seen
    new, labels = performance(rng, 90, noise=1.0)
    base = DTWOptions(cost="euclidean", path_length_weighting=True)
    plain = aligned_pairs(cost_matrix(new, ref), base)
    weighted = aligned_pairs(cost_matrix(new, ref, "euclidean", opt.weights_), base)
    assert alignment_error(weighted, labels, ref_labels) < alignment_error(
        plain, labels, ref_labels
    )
