"""Gesture-Based DTW (paper 001): segmentation, scores, guidance, Bayes threshold, baseline."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from analysis.dtw import DTWOptions
from analysis.online.gbdtw import (
    BayesThreshold,
    GBDTWOptions,
    cross_correlation_shift,
    guidance_runs,
    score,
    segment,
    shift_path,
)


def bump(frames: int, amplitude: float = 1.0) -> np.ndarray:
    """An arm raised and lowered: 0 -> amplitude -> 0 over ``frames`` frames."""
    return amplitude * np.sin(np.linspace(0.0, np.pi, frames)) ** 2


def gesture(rest_before: int, frames: int, rest_after: int, amplitude: float = 1.0) -> np.ndarray:
    return np.concatenate([np.zeros(rest_before), bump(frames, amplitude), np.zeros(rest_after)])


TUTOR = np.concatenate([gesture(5, 30, 5), gesture(5, 30, 5), gesture(5, 30, 5)])[:, None]
TUTOR_GESTURES = [(0, 39), (40, 79), (80, 119)]


def user_stream(seed: int = 0) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """Three gestures: late start, slower second gesture, smaller third; plus bump spans."""
    parts = [gesture(12, 30, 8), gesture(6, 45, 8), gesture(5, 30, 25, amplitude=0.6)]
    spans, start = [], 0
    for p, before in zip(parts, (12, 6, 5), strict=True):
        nonzero = np.flatnonzero(p > 1e-9)
        spans.append((start + before, start + int(nonzero[-1])))
        start += len(p)
    noise = 0.003 * np.random.default_rng(seed).standard_normal(start)
    return (np.concatenate(parts) + noise)[:, None], spans


def test_segments_each_gesture_in_the_rest_after_it() -> None:
    stream, spans = user_stream()
    result = segment(TUTOR, TUTOR_GESTURES, stream, GBDTWOptions(score_scale=0.1))
    assert len(result.gestures) == 3
    for g, (_, last) in zip(result.gestures, spans, strict=True):
        assert g.end >= last  # the whole bump is inside the gesture
        next_start = spans[g.index + 1][0] if g.index + 1 < len(spans) else len(stream)
        assert g.end < next_start
    assert result.gestures[1].start == result.gestures[0].end + 1
    # fewer cells than full DTW of the tutor against the whole stream (eq 12)
    assert result.cells < len(TUTOR) * len(stream)
    path = result.path
    assert path[0].tolist() == [0, 0] and path[-1, 1] == result.gestures[-1].end


def test_the_tutor_itself_scores_100() -> None:
    assert [g.score for g in segment(TUTOR, [(0, 119)], TUTOR).gestures] == [100.0]
    # With sensor noise the end test fires where the rest after each bump begins (001: the user
    # holds the end pose, the next e frames all match the gesture's last frame).
    noisy = TUTOR + 1e-3 * np.random.default_rng(2).standard_normal(TUTOR.shape)
    result = segment(TUTOR, TUTOR_GESTURES, noisy, GBDTWOptions(score_scale=0.1))
    assert all(g.score > 99.0 for g in result.gestures)
    for g, bump_end in zip(result.gestures, (34, 74, 114), strict=True):
        assert bump_end <= g.end <= bump_end + 6


def test_scores_drop_with_worse_performances() -> None:
    stream, _ = user_stream()
    g = segment(TUTOR, TUTOR_GESTURES, stream, GBDTWOptions(score_scale=0.05)).gestures
    assert all(0.0 <= x.score <= 100.0 for x in g)
    assert g[2].score < g[0].score  # the incomplete gesture
    assert score(0.0, 1.0) == 100.0 and score(1.0, 1.0) == pytest.approx(100 / np.e)


def test_guidance_types() -> None:
    stream, _ = user_stream()
    opt = GBDTWOptions(score_scale=0.1, guidance_share=0.15)
    g = segment(TUTOR, TUTOR_GESTURES, stream, opt).gestures
    assert "too slow" in g[1].guidance
    assert "incomplete" in g[2].guidance
    insensitive = GBDTWOptions(dtw=DTWOptions(speed_insensitive=True), guidance_share=0.15)
    g2 = segment(TUTOR, TUTOR_GESTURES, stream, insensitive).gestures
    assert "too slow" not in g2[1].guidance  # speed does not matter: types 1 and 2 are dropped


def test_overdone_and_too_fast_runs() -> None:
    tutor = bump(30)[:, None]
    higher = bump(30, amplitude=1.5)[:, None]
    over_the_top = np.array([[13, j] for j in range(12, 17)])  # user frames 12-16 rise and fall
    runs = guidance_runs(tutor, higher, over_the_top, GBDTWOptions())
    assert [r.type for r in runs] == [3]  # one tutor frame, a non-monotonic user stretch
    path_fast = np.array([[0, 0], [1, 1], [2, 1], [3, 1], [4, 2]])
    runs = guidance_runs(
        np.arange(5.0)[:, None], np.arange(3.0)[:, None], path_fast, GBDTWOptions()
    )
    assert [r.type for r in runs] == [1]  # several monotonic tutor frames on one user frame
    assert runs[0].tutor == (1, 3) and runs[0].user == (1, 1)


def test_bayes_threshold_midpoint_and_density_equality() -> None:
    rng = np.random.default_rng(1)
    passed = 80 + 5 * rng.standard_normal(400)
    failed = 50 + 5 * rng.standard_normal(400)
    scores = np.concatenate([passed, failed])
    labels = np.concatenate([np.zeros(400, bool), np.ones(400, bool)])
    bt = BayesThreshold().fit(scores, labels)
    assert bt.threshold_ == pytest.approx(bt.means_.mean(), abs=1.0)
    assert bt.predict([90.0, 30.0]).tolist() == [False, True]
    # unequal spreads and priors: the threshold still equalises prior-weighted densities (eq 13)
    bt2 = BayesThreshold(priors=(0.7, 0.3)).fit(
        np.concatenate([passed, 55 + 12 * rng.standard_normal(400)]), labels
    )
    s0 = bt2.threshold_
    lhs = stats.norm.pdf(s0, bt2.means_[0], bt2.stds_[0]) * 0.7
    rhs = stats.norm.pdf(s0, bt2.means_[1], bt2.stds_[1]) * 0.3
    assert lhs == pytest.approx(rhs, rel=1e-6)
    assert bt2.means_[1] < s0 < bt2.means_[0]
    with pytest.raises(ValueError):
        BayesThreshold().fit([1.0, 2.0, 3.0], [False, False, False])


def test_cross_correlation_recovers_a_shift() -> None:
    f = np.concatenate([np.zeros(10), bump(30), np.zeros(30)])
    g = np.concatenate([np.zeros(7), f[:-7]])  # f delayed by 7 frames
    tau = cross_correlation_shift(f, g)
    assert tau == 7
    pairs = shift_path(len(f), len(g), tau)
    assert pairs[0].tolist() == [0, 7] and pairs[-1].tolist() == [len(f) - 8, len(g) - 1]
    np.testing.assert_allclose(f[pairs[:, 0]], g[pairs[:, 1]])
