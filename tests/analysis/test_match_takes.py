"""Confirmed takes in the fit check (`analysis.pipeline.match`): an exercise is as near as the
nearest of its reference and its takes confirmed as correct, and with enough takes for every
exercise compared the nearest exercise fits and no other (one rule before and after a move)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import read
from analysis.pipeline import analyse, build_model
from analysis.pipeline.match import Candidate, MatchContext, MatchOptions, features_of
from tests.analysis.test_match import marks

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
# people whose correct takes the clinic confirmed: not the reference's (s01), not s03's
CONFIRMED_BY = ("s02", "s04", "s05", "s06", "s07")


def session(name: str):
    return read(DATA / f"sessions/{name}.bvh.gz")


@pytest.fixture(scope="module")
def clinic():
    """Deep squat (m01) and sit to stand (m05): models from s01's correct takes, and five other
    people's correct takes of each."""
    models, takes = {}, {}
    for exercise in ("m01", "m05"):
        name = f"sessions/{exercise}_s01_correct.bvh.gz"
        models[exercise] = build_model(read(DATA / name), *marks(name))
        takes[exercise] = tuple(
            features_of(session(f"{exercise}_{who}_correct")) for who in CONFIRMED_BY
        )
    return models, takes


def contexts(models, takes) -> dict[str, MatchContext]:
    """Each exercise analysed with the other as the clinic's candidate (``takes``: {} for the
    reference alone)."""
    names = {"m01": "a deep squat", "m05": "sit to stand"}
    out = {}
    for own, other in (("m01", "m05"), ("m05", "m01")):
        features = features_of(models[other].tutor)
        candidate = Candidate(other, names[other], features, takes.get(other, ()))
        out[own] = MatchContext(names[own], (candidate,), own_takes=takes.get(own, ()))
    return out


def test_the_margin_follows_the_takes_of_every_exercise_compared():
    options = MatchOptions()
    five = tuple(np.zeros((4, 17)) for _ in range(5))
    full = Candidate("a", "a", np.zeros((4, 17)), five)
    short = Candidate("b", "b", np.zeros((4, 17)), five[:2])
    assert MatchContext("x", (full,), own_takes=five).fewest_takes() == 6
    assert options.margin_for(MatchContext("x", (full,), own_takes=five)) == 1.0
    # one exercise with fewer takes: the reference's margin for all (same test after a move)
    assert options.margin_for(MatchContext("x", (full, short), own_takes=five)) == options.margin
    assert options.margin_for(MatchContext("x", (full,), own_takes=five[:4])) == options.margin
    assert options.margin_for(MatchContext("x", (), own_takes=five)) == options.margin
    other_recorder = MatchContext("x", (full,), same_recorder=False, own_takes=five)
    assert options.margin_for(other_recorder) == options.cross_recorder_margin


def test_confirmed_takes_tell_a_sit_to_stand_from_the_squat(clinic):
    """s03's sit to stand is nearer the squat's reference than its own: with the references
    alone it passes as a squat; with the clinic's confirmed takes it is told it looks like sit
    to stand, and moved there it fits."""
    models, takes = clinic
    take = session("m05_s03_correct")
    alone = contexts(models, {})
    assert analyse(take, models["m01"], match=alone["m01"]).summary.match.fits
    confirmed = contexts(models, takes)
    as_squat = analyse(take, models["m01"], match=confirmed["m01"]).summary
    assert not as_squat.match.fits and as_squat.match.looks_like == "m05"
    assert "It looks more like sit to stand." in as_squat.match.message
    assert as_squat.repetitions == () and as_squat.score is None
    moved = analyse(take, models["m05"], match=confirmed["m05"]).summary
    assert moved.match.fits and any(r.passed for r in moved.repetitions)


def test_with_confirmed_takes_a_squat_still_fits_and_is_refused_as_sit_to_stand(clinic):
    models, takes = clinic
    confirmed = contexts(models, takes)
    squat = session("m01_s03_incorrect")
    assert analyse(squat, models["m01"], match=confirmed["m01"]).summary.match.fits
    moved = analyse(squat, models["m05"], match=confirmed["m05"]).summary.match
    assert not moved.fits and moved.looks_like == "m01"
