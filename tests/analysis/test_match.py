"""The fit check (`analysis.pipeline.match`): a recording of another exercise is a result with no
repetition and no score that says so; sessions of the right exercise, correct or not, fit."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import read
from analysis.pipeline import AnalysisSummary, analyse, build_model
from analysis.pipeline.match import (
    Candidate,
    Evidence,
    MatchContext,
    MatchOptions,
    Ranking,
    decide,
    distances,
    features_of,
)
from analysis.pipeline.results import ExerciseMatch
from analysis.retrieval.features import MIRROR_ORDER, mirrored_features

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"


def marks(name: str) -> tuple[list[int], list[int]]:
    for line in (DATA / "landmarks.csv").read_text().splitlines():
        if line.startswith(name):
            _, frames, types = line.split(",")
            return [int(v) for v in frames.split(";")], [int(v) for v in types.split(";")]
    raise LookupError(name)


@pytest.fixture(scope="module")
def models():
    out = {}
    for exercise in ("m01", "m07"):
        name = f"sessions/{exercise}_s01_correct.bvh.gz"
        out[exercise] = build_model(read(DATA / name), *marks(name))
    return out


def session(name: str):
    return read(DATA / f"sessions/{name}.bvh.gz")


def test_another_exercise_is_not_scored_and_names_what_it_looks_like(models):
    arms = Candidate("arms-id", "a shoulder abduction", features_of(models["m07"].tutor))
    context = MatchContext("a deep squat", (arms,))
    summary = analyse(session("m07_s03_correct"), models["m01"], match=context).summary
    assert not summary.match.fits and summary.match.looks_like == "arms-id"
    assert summary.match.message.startswith("This recording does not look like a deep squat")
    assert "It looks more like a shoulder abduction." in summary.match.message
    assert summary.repetitions == () and summary.score is None and summary.gamma == {}
    assert summary.clinical_angles  # what can be measured still is
    as_json = summary.to_json()
    assert as_json["score"] is None and as_json["match"]["fits"] is False
    assert AnalysisSummary.from_json(as_json).match == summary.match


def test_sessions_of_the_exercise_fit_correct_or_not(models):
    arms = Candidate("arms-id", "a shoulder abduction", features_of(models["m07"].tutor))
    context = MatchContext("a deep squat", (arms,))
    for name in ("m01_s02_correct", "m01_s05_incorrect"):
        summary = analyse(session(name), models["m01"], match=context).summary
        assert summary.match.fits, name
        assert summary.to_json()["match"] == {"fits": True}
        assert summary.repetition_count >= 9 and summary.score is not None


def test_without_candidates_no_exercise_is_named(models):
    summary = analyse(session("m01_s04_correct"), models["m07"]).summary
    assert not summary.match.fits and summary.match.looks_like is None
    assert (
        "this exercise" in summary.match.message and "looks more like" not in summary.match.message
    )


def evidence(**changes) -> Evidence:
    base = {"repetitions": 10, "progress": 1.0, "profile": 0.95, "own_motion": 1.0}
    return Evidence(**{**base, **changes})


def test_each_kind_of_evidence_decides_with_its_reason():
    context, options = MatchContext("a deep squat"), MatchOptions()
    assert decide(evidence(), context, options).fits
    reasons = {
        "we found no repetition": evidence(repetitions=0),
        "hardly move": evidence(progress=0.1, own_motion=0.1),
        "other body parts move": evidence(profile=0.3),
        "much closer to another exercise": evidence(nearer=3.0),
    }
    for words, found in reasons.items():
        match = decide(found, context, options)
        assert not match.fits and words in match.message, words
    # a small range alone is a patient's limit, not another exercise
    assert decide(evidence(progress=0.1, own_motion=0.6), context, options).fits
    # nearer but within the margin: the recording still fits (similar exercises exist)
    assert decide(evidence(nearer=options.margin * 0.9), context, options).fits


def test_runs_stored_before_the_check_read_as_fitting():
    old = AnalysisSummary.from_json({"frames": 10, "fps": 30.0, "score": 55.0})
    assert old.match == ExerciseMatch() and old.score == 55.0
    assert ExerciseMatch.from_json({"fits": False, "message": "m", "looks_like": None}).message


def test_a_take_done_with_the_other_side_is_at_no_distance():
    rng = np.random.default_rng(7)
    take = rng.random((40, 17))
    assert sorted(MIRROR_ORDER) == list(range(17))
    assert np.array_equal(mirrored_features(mirrored_features(take)), take)
    other_side = mirrored_features(take)
    assert distances(other_side, [take, rng.random((40, 17))])[0] == pytest.approx(0.0)


def test_the_named_exercises_are_those_the_distance_test_accepts():
    a, b, c = (Candidate(k, k, np.zeros((1, 17))) for k in "abc")
    ranking = Ranking(own=1.0, others=((0.5, a), (0.6, b), (0.9, c)))
    assert ranking.nearer() == pytest.approx(2.0)
    assert ranking.named(1.3) == (a, b)  # c is more than 1.3 times farther than a
    assert ranking.named(1.1) == (a,)
    assert Ranking(own=0.5, others=((0.6, a),)).named(1.3) == ()  # nothing nearer than own
    match = decide(evidence(nearer=2.0, nearest=a, also=b), MatchContext("x"), MatchOptions())
    assert not match.fits and match.looks_like == "a"
    assert "It looks more like a or b." in match.message


def test_one_rule_before_and_after_a_move(models):
    """The clinic holds both exercises: an abduction analysed as the squat names the abduction;
    moved there it fits; a squat moved to the abduction is told so again."""
    squat = Candidate("squat-id", "a deep squat", features_of(models["m01"].tutor))
    arms = Candidate("arms-id", "a shoulder abduction", features_of(models["m07"].tutor))
    as_squat = MatchContext("a deep squat", (arms,))
    as_arms = MatchContext("a shoulder abduction", (squat,))
    abduction = session("m07_s04_incorrect")
    before = analyse(abduction, models["m01"], match=as_squat).summary.match
    assert not before.fits and before.looks_like == "arms-id"
    assert analyse(abduction, models["m07"], match=as_arms).summary.match.fits
    moved = analyse(session("m01_s03_incorrect"), models["m07"], match=as_arms).summary
    assert not moved.match.fits and moved.match.looks_like == "squat-id"
    assert moved.repetitions == () and moved.score is None
