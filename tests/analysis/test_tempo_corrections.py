"""Issue 26, item 4: tempo told as a correction by the one pace rule (paper 001's, live and
offline), judged against the tutor's pace and, from a later session on, the patient's own; the
repetitions' excursion is stored so that a later session can be judged against this one."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analysis.assessment.findings import RepetitionMeasures, findings
from analysis.bvh import read
from analysis.pipeline import analyse, build_model
from analysis.pipeline.gestures import Pace
from analysis.pipeline.results import RepetitionResult
from tests.analysis.guidance_cases import retimed
from tests.analysis.test_pipeline import landmarks

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
KNEE = {"knee_flexion_left": 100.0}


def _reps(tempo: float, pace: tuple[str, ...], passed: bool = True) -> list[RepetitionMeasures]:
    return [RepetitionMeasures(30 * k, KNEE, tempo, passed, pace=pace) for k in range(4)]


def test_the_pace_rule_tells_a_passed_recording_its_tempo() -> None:
    found = findings(_reps(0.55, ("too fast",)), KNEE, passed=True)
    assert [f.kind for f in found if f.kind != "good"] == ["fast"]
    assert found[0].amount == pytest.approx(45.0)
    found = findings(_reps(1.7, ("too slow",)), KNEE, passed=True)
    assert found[0].kind == "slow" and found[0].amount == pytest.approx(70.0)


def test_no_tempo_correction_without_the_rule_or_against_the_tutors_pace() -> None:
    # the rule said nothing: a passed recording is not told its tempo
    assert all(f.kind == "good" for f in findings(_reps(0.7, ()), KNEE, passed=True))
    # too fast for this patient's own (slow) pace, but slower than the tutor: "slow down,
    # each repetition took 120 % of the demonstration's time" could not be true
    assert all(f.kind == "good" for f in findings(_reps(1.2, ("too fast",)), KNEE, passed=True))
    assert all(f.kind == "good" for f in findings(_reps(0.8, ("too slow",)), KNEE, passed=True))


def test_a_failed_repetition_far_off_the_tutors_pace_is_still_told() -> None:
    found = findings(_reps(0.5, (), passed=False), KNEE)
    assert any(f.kind == "fast" for f in found)


def test_the_excursion_is_stored_and_read_back() -> None:
    rep = RepetitionResult(start=0, end=10, peak=5, score=80.0, tempo=0.9, excursion=0.97)
    assert RepetitionResult.from_json(rep.to_json()).excursion == pytest.approx(0.97)
    older = {k: v for k, v in rep.to_json().items() if k != "excursion"}
    assert RepetitionResult.from_json(older).excursion is None


@pytest.fixture(scope="module")
def raise_model():
    name = "sessions/m07_s01_correct.bvh.gz"
    return build_model(read(DATA / name), *landmarks(name))


@pytest.mark.parametrize(("factor", "direction"), [(0.6, "slow down"), (1.6, "speed up")])
def test_a_retimed_session_against_its_own_earlier_pace(raise_model, factor, direction) -> None:
    motion = read(DATA / "sessions/m07_s02_correct.bvh.gz")
    plain = analyse(motion, raise_model).summary
    assert all(r.excursion is not None and r.excursion > 0.5 for r in plain.repetitions)
    tempo = float(np.median([r.tempo for r in plain.repetitions]))
    own = Pace(tempo, float(np.median([r.excursion for r in plain.repetitions])), earlier=True)
    # the same session as its own earlier one: nothing about tempo
    again = analyse(motion, raise_model, own_pace=own).summary
    assert all(c.direction not in ("slow down", "speed up") for c in again.advice.corrections)
    changed = analyse(retimed(motion, factor), raise_model, own_pace=own).summary
    first = changed.advice.corrections[0]
    assert first.direction == direction
