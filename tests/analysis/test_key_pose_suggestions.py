"""Key poses suggested on an unannotated tutor: rest → extreme → rest, near the labelled frames."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from analysis.bvh import read
from analysis.landmarks import suggest_key_poses

UI_PRMD = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"


def labelled_reps() -> list[tuple[str, list[int], list[int]]]:
    with open(UI_PRMD / "landmarks.csv", newline="") as handle:
        rows = [r for r in csv.DictReader(handle) if r["file"].startswith("reps/")]
    return [
        (
            r["file"],
            [int(v) for v in r["frames"].split(";")],
            [int(v) for v in r["types"].split(";")],
        )
        for r in rows
    ]


def test_most_labelled_repetitions_get_the_labelled_key_poses():
    matched, offsets = 0, []
    reps = labelled_reps()
    for name, frames, types in reps:
        suggestion = suggest_key_poses(read(UI_PRMD / name))
        if suggestion.types.tolist() == types:
            matched += 1
            offsets.append(np.abs(np.subtract(suggestion.frames, frames)).max())
    assert matched >= 0.9 * len(reps)
    assert np.median(offsets) <= 3


def test_a_still_recording_gets_no_suggestion():
    motion = read(UI_PRMD / labelled_reps()[0][0])
    still = motion.frames.copy()
    still[:] = still[0]
    suggestion = suggest_key_poses(type(motion)(motion.skeleton, still, motion.frame_time))
    assert len(suggestion) == 0 and suggestion.types.size == 0
