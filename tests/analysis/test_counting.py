"""Live repetition counting: the offline segmenter's rules applied one frame at a time."""

from __future__ import annotations

import itertools

import numpy as np

from analysis.landmarks.segmentation import clean_progress, segment
from analysis.online.counting import RepetitionCounter


def humps(heights: list[float], rep: int = 60, rest: int = 20, seed: int = 0) -> np.ndarray:
    """A progress signal: a rest, then one raised-cosine hump per height, each followed by a
    rest, with a little sensor noise."""
    rng = np.random.default_rng(seed)
    parts = [np.zeros(rest)]
    for h in heights:
        parts += [h * 0.5 * (1 - np.cos(np.linspace(0, 2 * np.pi, rep))), np.zeros(rest)]
    signal = np.concatenate(parts)
    return signal + rng.normal(0.0, 0.01, signal.size)


def count(signal: np.ndarray, rep: float) -> tuple[RepetitionCounter, list[tuple[int, int]]]:
    """Counted repetitions with the frame (number of values pushed) each was reported at."""
    counter = RepetitionCounter(rep)
    reported = []
    for k, value in enumerate(signal):
        reported += [(k, c.peak) for c in counter.push(value)]
    reported += [(signal.size, c.peak) for c in counter.finish()]
    return counter, reported


def test_cleaning_equals_the_offline_filters() -> None:
    signal = humps([1.0, 0.8, 1.1], seed=1)
    counter, _ = count(signal, 70.0)
    np.testing.assert_allclose(counter.clean.values, clean_progress(signal, 70.0), atol=1e-12)


def test_counts_what_the_offline_segmenter_counts_soon_after_each_return() -> None:
    signal = humps([1.0, 0.7, 1.2, 0.9, 1.0], seed=2)
    counter, reported = count(signal, 60.0)
    offline = segment(signal, 60.0)
    assert [c.peak for c in counter.counted] == offline.peaks.tolist()
    for (at, peak), c in zip(reported, counter.counted, strict=True):
        # reported once back near rest: within half a repetition and a look-ahead of the peak
        assert peak < at <= peak + 30 + counter.lag + 2
        assert c.start < c.peak < c.end
    assert all(a.end < b.start for a, b in itertools.pairwise(counter.counted))


def test_a_twitch_in_a_rest_and_a_half_return_are_not_repetitions() -> None:
    twitch = humps([1.0, 0.08, 1.0], seed=3)  # under the least prominence
    assert len(count(twitch, 60.0)[0].counted) == 2
    # two humps with a dip of a fifth of their height between them (a patient who half
    # returns): one repetition, as offline (relative prominence)
    t = np.linspace(0, 1, 90)
    dip = 1.0 - 0.2 * np.exp(-((t - 0.5) ** 2) / 0.005)
    double = np.concatenate([np.zeros(20), np.sin(np.pi * t) ** 0.3 * dip, np.zeros(20)])
    assert len(count(double, 60.0)[0].counted) == len(segment(double, 60.0).peaks) == 1


def test_a_repetition_cut_off_by_the_end_of_the_stream_counts() -> None:
    signal = humps([1.0, 1.0, 1.0], seed=4)[:-45]  # the last hump stops half way down
    counter, reported = count(signal, 60.0)
    assert len(counter.counted) == len(segment(signal, 60.0).peaks) == 3
    assert reported[-1][0] == signal.size  # the last one at the flush
