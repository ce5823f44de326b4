"""Issue 26: a recording in which the arm the exercise trains stays down finds no repetition and
"does not look like the exercise"; it is still told which part to move, and by how much."""

from __future__ import annotations

from pathlib import Path

import pytest

from analysis.bvh import read
from analysis.clinical import angle_series
from analysis.pipeline import analyse, build_model
from analysis.pipeline.advice_stage import tutor_reference
from analysis.pipeline.still_advice import WHOLE, still_findings
from tests.analysis.mistake_cases import arm_down
from tests.analysis.test_pipeline import landmarks

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
TUTOR = "sessions/m07_s01_correct.bvh.gz"  # shoulder abduction, right arm


@pytest.fixture(scope="module")
def model():
    return build_model(read(DATA / TUTOR), *landmarks(TUTOR))


def test_an_arm_left_down_is_told_to_rise_by_its_missing_excursion(model) -> None:
    still = arm_down(read(DATA / "sessions/m07_s02_correct.bvh.gz"), "Right")
    summary = analyse(still, model).summary
    assert not summary.match.fits and summary.score is None and not summary.repetitions
    first = summary.advice.corrections[0]
    assert (first.part, first.direction, first.unit) == ("right arm", "raise", "°")
    # the tutor's arm rises about 140°, this one not at all: the loss is nearly all of it
    tutor = tutor_reference(model).ranges[first.angle]
    assert first.angle == "shoulder_elevation_right" and tutor > 100.0
    assert first.amount == pytest.approx(tutor, abs=5.0)
    assert first.text.endswith(f"in {WHOLE}.") and first.repetitions == ()
    assert [c.text for c in summary.feedback] == [c.text for c in summary.advice.corrections]


def test_a_recording_that_moves_the_exercises_parts_gets_no_such_correction(model) -> None:
    # the tutor's own recording, and a correct session: every involved angle moved
    assert still_findings(angle_series(model.tutor), model) == []
    moving = angle_series(read(DATA / "sessions/m07_s03_correct.bvh.gz"))
    assert still_findings(moving, model) == []
