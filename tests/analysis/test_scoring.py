"""Repetition scores: features against the tutor, trained scorer, and a patient who uses the
other side (analysis/assessment/scoring.py, with the pipeline's scoring stage)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from analysis.assessment.scoring import fit_scorer, joint_reach, repetition_features
from analysis.bvh import read
from analysis.pipeline import analyse, build_model

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"


def _rep(reach: float, n: int = 30, joints: int = 3) -> np.ndarray:
    """(n, 3J) movement relative to its start: joint 0 goes ``reach`` up and back, others rest."""
    out = np.zeros((n, 3 * joints))
    out[:, 1] = reach * np.sin(np.linspace(0.0, np.pi, n))
    return out


def test_features_are_zero_against_itself_and_show_a_short_reach() -> None:
    tutor = [_rep(1.0), _rep(0.9, 34)]
    assert np.allclose(repetition_features(tutor[0], tutor), 0.0)
    short = repetition_features(_rep(0.5), tutor)
    joints = 3
    assert short.shape == (2 * joints,)
    assert short[joints] < -0.3  # joint 0 reaches ~0.4 body sizes less than the closest tutor rep
    assert np.allclose(short[joints + 1 :], 0.0)
    assert np.allclose(joint_reach(_rep(0.7)), [0.7, 0.0, 0.0], atol=0.01)


def test_trained_score_ranks_correct_above_incorrect_and_keeps_the_tutor_share() -> None:
    rng = np.random.default_rng(1)
    tutor = [_rep(1.0 + 0.02 * k, 30 + k) for k in range(4)]
    good = [_rep(1.0 + 0.05 * rng.normal(), 30) for _ in range(20)]
    bad = [_rep(0.5 + 0.05 * rng.normal(), 30) for _ in range(20)]
    labelled = [(repetition_features(r, tutor), True) for r in good]
    labelled += [(repetition_features(r, tutor), False) for r in bad]
    scorer = fit_scorer(tutor, labelled)
    assert scorer.source == "labelled recordings"
    good_score = scorer.score(repetition_features(_rep(1.0), tutor))
    bad_score = scorer.score(repetition_features(_rep(0.5), tutor))
    assert 0.0 <= bad_score < good_score <= 100.0
    cold = fit_scorer(tutor).score(repetition_features(_rep(1.0), tutor))
    assert cold > 90.0


def _landmarks(name: str) -> tuple[list[int], list[int]]:
    with open(DATA / "landmarks.csv") as handle:
        row = next(r for r in csv.DictReader(handle) if r["file"] == name)
    return [int(v) for v in row["frames"].split(";")], [int(v) for v in row["types"].split(";")]


def test_a_patient_using_the_other_arm_is_scored_on_the_tutor_side() -> None:
    # UI-PRMD subject s07 raises the other arm in the shoulder exercises: the repetitions are
    # found on the mirror image, and must be scored on it too (not as a wrong arm movement)
    name = "sessions/m10_s01_correct.bvh.gz"
    model = build_model(read(DATA / name), *_landmarks(name))
    result = analyse(read(DATA / "sessions/m10_s07_correct.bvh.gz"), model).to_json()
    assert result["mirrored"] is True
    assert len(result["repetitions"]) == 10
    assert result["score"] > 50.0
