"""Anatomical joint angles: known poses of synthetic rigs (Kinect and Mixamo names, T-pose rest,
any heading), the positions-only cross-check on UI-PRMD, ranges and norms."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import read
from analysis.clinical import (
    ANGLE_NAMES,
    angle_ranges,
    angle_series,
    clinical_angles,
    norm_for,
)
from analysis.pipeline.results import AngleRange
from tests.synthetic_poses import MIXAMO_NAMES, posed, rot

UI_PRMD = Path(__file__).resolve().parents[2] / "data" / "ui-prmd" / "sessions"
TOL = 2.0

# One plane at a time: (pose as world rotations of segments, angle, expected degrees).
KNOWN = [
    ({"LeftLowerLeg": rot("x", 90.0)}, "knee_flexion_left", 90.0),
    ({"RightLowerLeg": rot("x", 90.0)}, "knee_flexion_right", 90.0),
    ({"LeftUpperArm": rot("z", 30.0)}, "shoulder_abduction_left", 120.0),
    ({"RightUpperArm": rot("z", -30.0)}, "shoulder_abduction_right", 120.0),
    ({"LeftUpperArm": rot("y", -90.0)}, "shoulder_flexion_left", 90.0),
    ({"LeftForearm": rot("x", -45.0) @ rot("z", -90.0)}, "elbow_flexion_left", 45.0),
    ({"RightForearm": rot("x", -45.0) @ rot("z", 90.0)}, "elbow_flexion_right", 45.0),
    ({"LeftUpperLeg": rot("x", -60.0)}, "hip_flexion_left", 60.0),
    ({"RightUpperLeg": rot("x", -60.0)}, "hip_flexion_right", 60.0),
    ({"LeftUpperLeg": rot("z", 30.0)}, "hip_abduction_left", 30.0),
    ({"RightUpperLeg": rot("z", -30.0)}, "hip_abduction_right", 30.0),
    ({"LeftFoot": rot("x", -15.0)}, "ankle_dorsiflexion_left", 15.0),
    ({"Spine": rot("x", 30.0)}, "trunk_flexion", 30.0),
    ({"Spine": rot("z", 20.0)}, "trunk_lateral_flexion", 20.0),
]


def at(pose: dict, heading: float = 0.0, names=None) -> dict[str, float]:
    """Angles of one pose of the whole body turned by ``heading`` degrees about the vertical."""
    turn = rot("y", heading)
    world = {"Waist": turn, **{k: turn @ v for k, v in pose.items()}}
    for arm, hang in (("LeftUpperArm", rot("z", -90.0)), ("RightUpperArm", rot("z", 90.0))):
        world.setdefault(arm, turn @ hang)
    series = angle_series(posed([world], names))
    return {k: float(v[0]) for k, v in series.items()}


def test_anatomical_pose_is_zero_although_the_rest_pose_is_a_t_pose():
    angles = at({})
    assert set(angles) == set(ANGLE_NAMES)
    assert all(abs(v) < 1e-6 for v in angles.values()), angles


@pytest.mark.parametrize(("pose", "name", "expected"), KNOWN, ids=[k[1] for k in KNOWN])
@pytest.mark.parametrize("heading", [0.0, 135.0])
def test_known_angle_in_its_own_plane(pose, name, expected, heading):
    angles = at(pose, heading)
    assert angles[name] == pytest.approx(expected, abs=TOL)
    # The movement is in one plane: the other angles of the same joint stay near 0.
    joint = name.rsplit("_", 1)[0].split("_")[0]
    side = name.rsplit("_", 1)[-1]
    for other, value in angles.items():
        if other != name and other.startswith(joint) and other.endswith(side):
            assert abs(value) < TOL, (other, value)


def test_extension_and_adduction_are_negative():
    assert at({"LeftUpperArm": rot("y", 90.0) @ rot("z", -45.0)})["shoulder_flexion_left"] < -10
    assert at({"LeftUpperLeg": rot("x", 20.0)})["hip_flexion_left"] == pytest.approx(-20, abs=TOL)
    assert at({"LeftUpperLeg": rot("z", -15.0)})["hip_abduction_left"] == pytest.approx(
        -15, abs=TOL
    )
    assert at({"LeftFoot": rot("x", 30.0)})["ankle_dorsiflexion_left"] == pytest.approx(
        -30, abs=TOL
    )
    assert at({"Spine": rot("x", -10.0)})["trunk_flexion"] == pytest.approx(-10, abs=TOL)


def test_mixamo_names_give_the_same_angles():
    pose = {"LeftLowerLeg": rot("x", 90.0), "RightUpperArm": rot("z", -30.0)}
    kinect, mixamo = at(pose), at(pose, names=MIXAMO_NAMES)
    assert set(mixamo) == set(ANGLE_NAMES)
    assert mixamo == pytest.approx(kinect, abs=1e-9)


def test_angles_a_skeleton_cannot_give_are_absent():
    from tests.synthetic_motion import skeleton  # no feet, no collars, legs end at the knee

    sk = skeleton()
    from analysis.bvh import Motion

    angles = angle_series(Motion(sk, np.zeros((3, sk.n_channels)), 1 / 30))
    assert "ankle_dorsiflexion_left" not in angles and "knee_flexion_left" not in angles
    assert {"elbow_flexion_left", "shoulder_abduction_right", "trunk_flexion"} <= set(angles)
    assert abs(angles["shoulder_abduction_left"][0] - 90.0) < TOL  # its rest pose is a T-pose


@pytest.mark.parametrize(
    "name", ["m01_s02_correct", "m05_s03_incorrect", "m07_s01_correct", "m10_s06_correct"]
)
def test_orientation_and_positions_agree_on_ui_prmd(name):
    motion = read(UI_PRMD / f"{name}.bvh.gz")
    by_rotation = angle_series(motion)
    by_position = angle_series(motion, method="positions")
    assert set(by_rotation) == set(ANGLE_NAMES) == set(by_position)
    worst = {k: float(np.nanmax(np.abs(by_rotation[k] - by_position[k]))) for k in ANGLE_NAMES}
    assert max(worst.values()) < 3.0, worst
    assert all(np.isfinite(v).all() for v in by_rotation.values())


def test_ui_prmd_ranges_are_plausible():
    squat = clinical_angles(read(UI_PRMD / "m01_s01_correct.bvh.gz"))
    assert squat["knee_flexion_left"].max > 90 and squat["hip_flexion_right"].max > 80
    assert squat["trunk_flexion"].range > 15
    abduction = clinical_angles(read(UI_PRMD / "m07_s01_correct.bvh.gz"))
    raised = max(
        abduction["shoulder_abduction_left"].max, abduction["shoulder_abduction_right"].max
    )
    assert raised > 100
    assert abduction["knee_flexion_left"].range < 20  # standing still


def test_angle_ranges_per_repetition_include_both_ends():
    series = {"knee_flexion_left": np.array([0.0, 10.0, 90.0, 40.0, np.nan, 5.0])}
    whole = angle_ranges(series)
    assert whole == {"knee_flexion_left": AngleRange(0.0, 90.0)}
    assert whole["knee_flexion_left"].range == 90.0
    assert angle_ranges(series, 1, 3) == {"knee_flexion_left": AngleRange(10.0, 90.0)}
    assert angle_ranges(series, 4, 4) == {}  # no finite value there
    assert angle_ranges(series, 3)["knee_flexion_left"] == AngleRange(5.0, 40.0)


def test_norms_cover_every_angle():
    for name in ANGLE_NAMES:
        norm = norm_for(name)
        assert norm.minimum <= 0 < norm.maximum and "AAOS" in norm.source
    assert norm_for("knee_flexion_right").maximum == 135.0
    assert norm_for("knee_flexion").percent_of_maximum(67.5) == pytest.approx(50.0)
    with pytest.raises(KeyError):
        norm_for("wrist_flexion_left")


def test_plain_words_and_regions():
    from analysis.clinical.labels import angle_groups, angle_label

    assert angle_label("knee_flexion_left") == "Left knee flexion"
    assert angle_label("shoulder_abduction_right") == "Right shoulder abduction"
    assert angle_label("trunk_flexion") == "Trunk flexion"
    assert all("_" not in angle_label(name) for name in ANGLE_NAMES)
    angles = {"trunk_flexion": AngleRange(0, 20), "knee_flexion_right": AngleRange(5, 95),
              "knee_flexion_left": AngleRange(3, 90)}  # fmt: skip
    groups = angle_groups(angles, involved_joints=["KneeLeft", "KneeRight"])
    assert [g["region"] for g in groups] == ["Knees", "Trunk"]  # the moved region first
    assert groups[0]["involved"] and not groups[1]["involved"]
    knee = groups[0]["rows"][0]
    assert (knee["label"], knee["range"], knee["norm_min"], knee["norm_max"]) == (
        "Left knee flexion", 87.0, 0.0, 135.0,
    )  # fmt: skip


def test_repetitions_carry_their_own_ranges_in_tenths_of_a_degree():
    from analysis.clinical.stored import repetition_angles
    from analysis.pipeline.results import RepetitionResult

    series = {"knee_flexion_left": np.array([0.04, 10.0, 90.06, 40.0, 20.0, 5.0])}
    reps = (RepetitionResult(0, 2, 1, 80.0), RepetitionResult(3, 5, 4, 70.0))
    first, second = repetition_angles(series, reps)
    assert first.clinical_angles == {"knee_flexion_left": AngleRange(0.0, 90.1)}
    assert second.clinical_angles == {"knee_flexion_left": AngleRange(5.0, 40.0)}
    assert first.to_json()["clinical_angles"] == {"knee_flexion_left": [0.0, 90.1]}  # compact
    assert RepetitionResult.from_json(first.to_json()) == first
    as_objects = {**first.to_json(), "clinical_angles": {"knee_flexion_left": {"min": 0, "max": 9}}}
    assert RepetitionResult.from_json(as_objects).clinical_angles["knee_flexion_left"].range == 9
    assert "clinical_angles" not in reps[0].to_json()  # absent when not measured: small JSON
    assert RepetitionResult.from_json(reps[0].to_json()).clinical_angles == {}
