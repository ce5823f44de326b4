"""Paper 001's guidance read off the warping path, on sessions with a mistake made on purpose
(`tests/analysis/guidance_cases.py`; the whole evaluation is `python -m bench.eval_guidance`)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import read
from analysis.kinematics import quaternions as quat
from analysis.kinematics import rotations
from analysis.pipeline import analyse, build_model
from analysis.pipeline.prepare import prepare
from analysis.pipeline.repetition_stage import session_pace
from tests.analysis.guidance_cases import modified, range_scaled, retimed

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"


def _landmarks(name: str) -> tuple[list[int], list[int]]:
    with open(DATA / "landmarks.csv") as handle:
        row = next(r for r in csv.DictReader(handle) if r["file"] == name)
    return [int(v) for v in row["frames"].split(";")], [int(v) for v in row["types"].split(";")]


@pytest.fixture(scope="module")
def squat():
    tutor = "sessions/m01_s01_correct.bvh.gz"
    model = build_model(read(DATA / tutor), *_landmarks(tutor))
    return model, read(DATA / "sessions/m01_s03_correct.bvh.gz")


def test_generator_retimes_and_scales_the_movement(squat):
    _, session = squat
    assert retimed(session, 1.6).n_frames == pytest.approx(1.6 * session.n_frames, rel=0.01)
    q, scaled = rotations(session), rotations(range_scaled(session, 0.6))
    knee = session.skeleton.names.index("LeftLowerLeg")
    moved = quat.angle_between(q[0, knee], q[:, knee], degrees=True)
    moved_scaled = quat.angle_between(scaled[0, knee], scaled[:, knee], degrees=True)
    assert moved_scaled.max() == pytest.approx(0.6 * moved.max(), rel=0.02)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("kind", "factor", "expected"), [("tempo", 1.6, "too slow"), ("range", 0.6, "incomplete")]
)
def test_the_mistake_is_named_first_with_its_frames(squat, kind, factor, expected):
    """Judged against the tutor and against this patient's pace in an earlier session (the
    unmodified take), as `bench.eval_guidance` does."""
    model, session = squat
    reps = analyse(session, model).summary.repetitions
    parts = model.components
    prepared = prepare(session, model.tutor.skeleton, model.fps, parts.axis.rep_frames)
    earlier = session_pace(prepared, [(r.start, r.end) for r in reps], model)
    summary = analyse(modified(session, kind, factor), model, own_pace=earlier).summary
    named = [r for r in summary.repetitions if r.main_guidance == expected]
    assert len(named) >= 0.7 * summary.repetition_count
    for rep in named:
        first, last = rep.guidance[0].frames
        assert rep.start <= first <= last <= rep.end


@pytest.mark.slow
def test_an_unmodified_correct_session_gets_little_guidance(squat):
    model, session = squat
    reps = analyse(session, model).summary.repetitions
    assert np.mean([not r.guidance for r in reps]) >= 0.7
