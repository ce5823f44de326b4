"""Issue 26: corrections about what the exercise trains, in agreement with pass/fail, and the
compensations (a trunk lean held all through, the trunk turning, a shoulder hiked, a knee
falling inward) as findings with an amount against the reference."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analysis.assessment.compensations import compensation_series
from analysis.assessment.findings import (
    SMALL_DEG,
    Reference,
    RepetitionMeasures,
    findings,
    involved_angles,
    plainly_off,
)
from analysis.bvh import read
from analysis.feedback import Grammar, default_grammar
from analysis.feedback.advice import advise
from analysis.pipeline import analyse, build_model
from tests.analysis.guidance_cases import range_scaled
from tests.analysis.mistake_cases import forward_lean
from tests.analysis.test_pipeline import landmarks

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
SQUAT = {"knee_flexion_left": 120.0, "knee_flexion_right": 118.0, "hip_flexion_left": 140.0,
         "hip_flexion_right": 138.0, "shoulder_flexion_left": 47.0, "ankle_dorsiflexion_left": 45.0,
         "trunk_flexion": 30.0}  # fmt: skip


def _reps(ranges: dict[str, float], n: int = 4, passed: bool = False, **middles: float) -> list:
    return [RepetitionMeasures(30 * k, ranges, 1.0, passed, middles) for k in range(n)]


def test_only_the_angles_the_exercise_trains_are_involved() -> None:
    # a squat: hips and knees; not the arms swung for balance, nor the (noisy) ankles
    assert involved_angles(SQUAT) == {
        "knee_flexion_left", "knee_flexion_right", "hip_flexion_left", "hip_flexion_right",
    }  # fmt: skip
    # an arm raise: one angle speaks for the arm, its elevation
    raise_ = {"shoulder_flexion_right": 142.0, "shoulder_abduction_right": 140.0,
              "shoulder_elevation_right": 141.0, "elbow_flexion_right": 16.0}  # fmt: skip
    assert involved_angles(raise_) == {"shoulder_elevation_right"}
    # the therapist's ticked joints narrow the set
    assert involved_angles(SQUAT, {"knee_left", "knee_right"}) == {
        "knee_flexion_left", "knee_flexion_right",
    }  # fmt: skip


def test_a_part_as_far_as_the_reference_is_never_also_too_little() -> None:
    tutor = {"shoulder_flexion_right": 119.0, "shoulder_elevation_right": 101.0}
    # the arm rose as far as the demonstration's (elevation), its "flexion" reads far less
    reps = _reps({"shoulder_flexion_right": 40.0, "shoulder_elevation_right": 98.0})
    found = findings(reps, tutor)
    assert [(f.kind, f.angle) for f in found] == [("good", "shoulder_elevation_right")]


def test_a_squat_that_passed_gets_no_large_correction_about_its_arms() -> None:
    reps = _reps({**SQUAT, "shoulder_flexion_left": 118.0, "knee_flexion_left": 60.0})
    failed = findings(reps, SQUAT)
    assert [(f.kind, f.angle) for f in failed if f.kind != "good"] == [
        ("less", "knee_flexion_left")
    ]  # the arm is no part of the squat: never "lower your left arm"
    assert failed[0].amount == pytest.approx(60.0)  # the loss in the knee's excursion
    # the same repetitions passed (each, or the recording): nothing of 10° or more is said
    said = findings(_reps(reps[0].ranges, passed=True), SQUAT)
    assert [f.kind for f in said if f.kind != "good"] == []
    kept = findings(reps, SQUAT, passed=True)
    assert all(f.amount < SMALL_DEG for f in kept if f.kind != "good")


def test_a_lean_held_all_through_is_found_and_said_with_its_amount() -> None:
    ref = Reference(SQUAT, middles={"trunk_flexion": 15.0, "trunk_lateral_flexion": 0.0})
    reps = _reps(SQUAT, trunk_flexion=36.0, trunk_lateral_flexion=1.0)  # same range, 21° more
    found = [f for f in findings(reps, ref) if f.kind != "good"]
    assert [(f.kind, f.angle, f.amount) for f in found] == [("held", "trunk_flexion", 21.0)]
    grammar = Grammar.parse(default_grammar(["LeftKnee"], ["start", "end of range"]))
    said = advise(grammar, found, 4, "knees").corrections[0]
    assert (said.part, said.direction, said.amount) == ("trunk", "straighten", 21.0)
    assert said.text.startswith("Straighten your trunk, by about 21°")
    # to the left, when the exercise is done with the other side: compared side for side
    sideways = _reps(SQUAT, trunk_flexion=15.0, trunk_lateral_flexion=-14.0)
    ref_right = Reference(SQUAT, middles={"trunk_flexion": 15.0, "trunk_lateral_flexion": 14.0})
    assert not [f for f in findings(sideways, ref_right, mirrored=True) if f.kind != "good"]
    assert findings(sideways, ref_right)[0].kind == "held_back"


def test_a_plain_error_fails_its_repetition_whatever_its_score() -> None:
    ref = Reference(SQUAT, middles={"trunk_flexion": 15.0})
    assert not plainly_off(_reps(SQUAT, trunk_flexion=20.0)[0], ref)
    short = {**SQUAT, "hip_flexion_left": 0.55 * 140.0}
    assert plainly_off(_reps(short, trunk_flexion=15.0)[0], ref)
    assert plainly_off(_reps(SQUAT, trunk_flexion=35.0)[0], ref)  # a 20° lean held
    # the arms are no main angle of a squat: their range decides nothing
    assert not plainly_off(_reps({**SQUAT, "shoulder_flexion_left": 5.0})[0], ref)


def _standing(frames: int) -> tuple[np.ndarray, dict[str, int]]:
    """Positions (y up, x to the right, z forward) of a person standing still, cm."""
    names = ("pelvis", "neck", "shoulder_left", "shoulder_right", "hip_left", "hip_right",
             "knee_left", "knee_right", "ankle_left", "ankle_right")  # fmt: skip
    roles = {name: k for k, name in enumerate(names)}
    points = [(0, 100, 0), (0, 150, 0), (-18, 145, 0), (18, 145, 0), (-10, 95, 0), (10, 95, 0),
              (-10, 50, 0), (10, 50, 0), (-10, 5, 0), (10, 5, 0)]  # fmt: skip
    return np.repeat(np.array(points, dtype=float)[None], frames, axis=0), roles


def test_compensations_read_the_turn_the_hike_and_the_knee_falling_in() -> None:
    pos, roles = _standing(2)
    up = np.array([0.0, 1.0, 0.0])
    turn = np.radians(30.0)  # frame 1: shoulders turned 30° about the vertical
    for joint, x in (("shoulder_left", -18.0), ("shoulder_right", 18.0)):
        pos[1, roles[joint]] = (x * np.cos(turn), 145.0, -x * np.sin(turn))
    pos[1, roles["knee_left"], 0] += 8.0  # the left knee falls inward (towards +x)
    pos[1, roles["shoulder_right"], 1] += 8.0  # the right shoulder hiked 8 cm
    series = compensation_series(pos, roles, up)
    assert abs(series["trunk_rotation"][1] - series["trunk_rotation"][0]) == pytest.approx(30.0)
    assert series["knee_valgus_left"][0] == pytest.approx(0.0, abs=1e-6)
    # 8 cm inside the hip → ankle line, seen from a 45.7 cm thigh; inward is positive
    assert series["knee_valgus_left"][1] == pytest.approx(
        np.degrees(np.arcsin(8 / np.hypot(8, 45)))
    )
    assert series["knee_valgus_right"][1] == pytest.approx(0.0, abs=1e-6)
    assert series["shoulder_hike_right"][1] - series["shoulder_hike_right"][0] > 15.0
    assert series["shoulder_hike_left"][1] == pytest.approx(series["shoulder_hike_left"][0])
    # a rig without hips has no trunk rotation nor knees
    no_hips = {k: v for k, v in roles.items() if not k.startswith(("hip", "knee", "ankle"))}
    assert set(compensation_series(pos, no_hips, up)) == {"shoulder_hike_left",
                                                          "shoulder_hike_right"}  # fmt: skip


@pytest.fixture(scope="module")
def raise_model():
    name = "sessions/m07_s01_correct.bvh.gz"
    return build_model(read(DATA / name), *landmarks(name))


def test_mistakes_made_on_purpose_fail_and_get_the_right_first_correction(raise_model) -> None:
    motion = read(DATA / "sessions/m07_s02_correct.bvh.gz")
    plain = analyse(motion, raise_model).summary
    assert plain.score >= plain.pass_threshold
    assert all(c.amount < SMALL_DEG for c in plain.advice.corrections)
    own = np.median([r.clinical_angles["shoulder_elevation_right"].range
                     for r in plain.repetitions])  # fmt: skip
    short = analyse(range_scaled(motion, 0.55), raise_model).summary
    assert short.score < short.pass_threshold
    first = short.advice.corrections[0]
    assert (first.part, first.direction) == ("right arm", "raise")
    lost = own - np.median([r.clinical_angles["shoulder_elevation_right"].range
                            for r in short.repetitions])  # fmt: skip
    assert abs(first.amount - lost) <= 0.4 * lost
    leaning, truth = forward_lean(motion)
    assert truth == pytest.approx(20.0, abs=2.0)
    bent = analyse(leaning, raise_model).summary
    assert bent.score < bent.pass_threshold
    first = bent.advice.corrections[0]
    assert (first.part, first.direction) == ("trunk", "straighten")
    assert abs(first.amount - truth) <= 0.4 * truth
