"""Repetitions from a cleaned landmark sequence (analysis/landmarks/repetitions.py)."""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from analysis.landmarks.repetitions import Repetition, repetitions
from analysis.periodic import clean

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
SIDES = [[1, 2], [3, 4]]  # left (start, end of range), right (start, end of range)


def _reps(frames: list[int], types: list[int], order: object, **kw: int) -> list[tuple]:
    out = repetitions(frames, types, order, **kw)  # type: ignore[arg-type]
    return [(r.start, r.peaks, r.end, r.complete, r.cycle) for r in out]


def test_one_cycle_shares_the_closing_start() -> None:
    reps = _reps([0, 41, 73, 109, 143], [1, 2, 1, 2, 1], [1, 2])
    assert reps == [(0, (41,), 73, True, 0), (73, (109,), 143, True, 0)]


def test_a_closed_cycle_means_the_same() -> None:
    frames, types = [0, 41, 73, 109, 143], [1, 2, 1, 2, 1]
    assert repetitions(frames, types, [1, 2, 1]) == repetitions(frames, types, [1, 2])
    assert repetitions(frames, types, [[1, 2, 1], [3, 4, 3]]) == repetitions(frames, types, SIDES)


def test_repetitions_are_frozen() -> None:
    rep = repetitions([0, 5, 9], [1, 2, 1], [1, 2])[0]
    assert isinstance(rep, Repetition)
    with pytest.raises(dataclasses.FrozenInstanceError):
        rep.start = 3  # type: ignore[misc]


def test_ankles_66_left_then_right() -> None:
    # eq 6.5: three left stretches (τ1, τ2) then three right ones (τ3, τ4)
    types = [1, 2, 1, 2, 1, 2, 1, 3, 4, 3, 4, 3, 4, 3]
    frames = list(range(0, 140, 10))
    reps = _reps(frames, types, SIDES)
    assert [r[4] for r in reps] == [0, 0, 0, 1, 1, 1]
    assert all(r[3] for r in reps)
    assert reps[3] == (70, (80,), 90, True, 1)


def test_patient_does_right_before_left_513() -> None:
    # tutor: left then right; patient: right then left (eq 5.13), with one extra left rep (5.12)
    types = [3, 4, 3, 4, 3, 1, 2, 1, 2, 1, 2, 1]
    frames = [10 * i for i in range(len(types))]
    reps = _reps(frames, types, SIDES)
    assert [r[4] for r in reps] == [1, 1, 0, 0, 0]
    assert all(r[3] for r in reps)
    assert reps[2][0] == 50  # the left side starts at its own start landmark


def test_alternating_sides() -> None:
    reps = _reps([0, 5, 10, 15, 20, 25, 30, 35, 40], [1, 2, 1, 3, 4, 3, 1, 2, 1], SIDES)
    assert [(r[0], r[2], r[4], r[3]) for r in reps] == [
        (0, 10, 0, True),
        (15, 25, 1, True),
        (30, 40, 0, True),
    ]


def test_incomplete_repetitions() -> None:
    # starts mid-repetition, ends before the closing start: both incomplete, ends as documented
    reps = _reps([5, 10, 20, 30, 35], [2, 1, 2, 1, 2], [1, 2], last_frame=99)
    assert reps == [(0, (5,), 10, False, 0), (10, (20,), 30, True, 0), (30, (35,), 99, False, 0)]
    assert _reps([0, 8], [1, 2], [1, 2])[0] == (0, (8,), 8, False, 0)  # default: last landmark


def test_missing_start_of_a_side() -> None:
    # the right side's first τ3 is missing: its repetition starts after the previous landmark
    reps = _reps([0, 10, 20, 30, 40, 50], [1, 2, 1, 4, 3, 1], SIDES)
    assert reps == [(0, (10,), 20, True, 0), (20, (30,), 40, False, 1)]


def test_start_without_movement_is_not_a_repetition() -> None:
    assert _reps([0, 10, 20, 30, 40], [1, 1, 2, 1, 1], [1, 2]) == [(10, (20,), 30, True, 0)]


def test_duplicate_and_out_of_order_peaks() -> None:
    rep = repetitions([0, 10, 12, 20], [1, 2, 2, 1], [1, 2])[0]
    assert rep.peaks == (10, 12) and rep.peak_types == (2, 2) and rep.complete
    three = [1, 2, 3]  # start, top, hold
    assert repetitions([0, 5, 9, 14], [1, 2, 3, 1], three)[0].complete
    assert not repetitions([0, 5, 9, 14], [1, 3, 2, 1], three)[0].complete
    assert not repetitions([0, 9, 14], [1, 3, 1], three)[0].complete  # the top is missing


def test_bad_input() -> None:
    with pytest.raises(ValueError, match="frames but"):
        repetitions([0, 1], [1], [1, 2])
    with pytest.raises(ValueError, match="time order"):
        repetitions([5, 1], [1, 2], [1, 2])
    with pytest.raises(ValueError, match="no cycle"):
        repetitions([0, 1], [1, 7], [1, 2])
    with pytest.raises(ValueError, match="one cycle"):
        repetitions([0], [1], [[1, 2], [2, 3]])
    assert repetitions([], [], [1, 2]) == []
    reps = repetitions(np.array([0, 4, 8]), np.array([1, 2, 1]), np.array([1, 2]))  # type: ignore[arg-type]
    assert reps[0].start == 0 and type(reps[0].end) is int


def _rows(name: str) -> dict[str, dict[str, str]]:
    with (DATA / name).open(newline="") as handle:
        return {row["file"]: row for row in csv.DictReader(handle)}


def test_ui_prmd_sessions_give_their_labelled_repetitions() -> None:
    landmarks, labels = _rows("landmarks.csv"), _rows("labels.csv")
    sessions = [f for f in landmarks if f.startswith("sessions/")][:20]
    assert sessions
    for name in sessions:
        frames = [int(v) for v in landmarks[name]["frames"].split(";")]
        types = [int(v) for v in landmarks[name]["types"].split(";")]
        reps = repetitions(frames, types, [1, 2])
        starts = [int(v) for v in labels[name]["rep_start_frames"].split(";")]
        assert len(reps) == int(labels[name]["rep_count"])
        assert [r.start for r in reps] == starts
        assert all(r.complete for r in reps)


def test_clean_then_segment_a_noisy_session() -> None:
    # a labelled session with an extra end-of-range and a right-side landmark inserted
    frames = [0, 41, 60, 73, 90, 109, 143, 179]
    types = [1, 2, 2, 1, 3, 2, 1, 2]
    kept = clean(types, [[1, 2, 1], [3, 4, 3]], method="ga-k", seed=0)
    assert 4 not in kept  # the stray τ3
    reps = repetitions([frames[i] for i in kept], [types[i] for i in kept], SIDES, last_frame=200)
    assert [(r.start, r.end, r.complete) for r in reps][:2] == [(0, 73, True), (73, 143, True)]
    assert reps[-1].complete is False and reps[-1].end == 200
