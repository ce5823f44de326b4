"""The fit check (`analysis.pipeline.match`): a recording of another exercise is a result with no
repetition and no score that says so; sessions of the right exercise, correct or not, fit."""

from __future__ import annotations

from pathlib import Path

import pytest

from analysis.bvh import read
from analysis.pipeline import AnalysisSummary, analyse, build_model
from analysis.pipeline.match import (
    Candidate,
    Evidence,
    MatchContext,
    MatchOptions,
    decide,
    features_of,
)
from analysis.pipeline.results import ExerciseMatch

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
