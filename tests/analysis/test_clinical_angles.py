"""Anatomical joint angles: known poses of four rigs (a synthetic Kinect-style T-pose rig, the
UI-PRMD Kinect skeleton and two CMU conversions from data/rigs, whose legs slant 20° outwards in
their rest pose and whose lower back, neck and collars are zero-length connector joints), every
angle in its own plane on each side, within 1°, at any heading; the arm forward (all flexion)
and diagonal (elevation split by its plane); the positions-only cross-check on UI-PRMD (the
knee-flexion range of every deep squat within 5°) and the UI-PRMD squatters' raised arms,
ranges and norms."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from analysis.bvh import Motion, Skeleton, read
from analysis.clinical import (
    ANGLE_NAMES,
    angle_ranges,
    angle_series,
    clinical_angles,
    measure,
    norm_for,
)
from analysis.pipeline.results import AngleRange
from tests.synthetic_poses import MIXAMO_NAMES, posed, rot

DATA = Path(__file__).resolve().parents[2] / "data"
UI_PRMD = DATA / "ui-prmd" / "sessions"
TOL = 1.0
# defined only with the arm raised or the elbow bent (analysis.clinical.angles): a hanging arm
# with a straight elbow gives neither
POSITIONAL = ("shoulder_plane_of_elevation", "shoulder_rotation")
ALWAYS_DEFINED = [n for n in ANGLE_NAMES if not n.startswith(POSITIONAL)]

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
    assert set(angles) == set(ALWAYS_DEFINED)
    assert all(abs(v) < 1e-6 for v in angles.values()), angles


@pytest.mark.parametrize(("pose", "name", "expected"), KNOWN, ids=[k[1] for k in KNOWN])
@pytest.mark.parametrize("heading", [0.0, 135.0])
def test_known_angle_in_its_own_plane(pose, name, expected, heading):
    angles = at(pose, heading)
    assert angles[name] == pytest.approx(expected, abs=TOL)
    # The movement is in one plane: the other angles of the same joint stay near 0, except the
    # shoulder's elevation, which is the arm's angle to the trunk in whatever plane.
    joint = name.rsplit("_", 1)[0].split("_")[0]
    side = name.rsplit("_", 1)[-1]
    if joint == "shoulder":
        assert angles[f"shoulder_elevation_{side}"] == pytest.approx(expected, abs=TOL)
    for other, value in angles.items():
        if other.startswith("shoulder_plane_of_elevation"):
            continue  # a direction: where the arm was raised to, not how far
        if other not in (name, f"shoulder_elevation_{side}") and other.startswith(joint):
            assert abs(value) < TOL or not other.endswith(side), (other, value)


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
    assert set(mixamo) == set(ALWAYS_DEFINED) | {"shoulder_plane_of_elevation_right"}
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
    # as read, before the body's limits leave frames out: both computations build the same frames
    by_rotation = angle_series(motion, within_body_limits=False)
    by_position = angle_series(motion, method="positions", within_body_limits=False)
    # (an ankle whose foot jumps while the person stands has no zero in either: issue 35)
    assert set(by_rotation) == set(by_position)
    assert set(ANGLE_NAMES) - set(by_rotation) <= {
        "ankle_dorsiflexion_left",
        "ankle_dorsiflexion_right",
    }
    assert all(
        np.isnan(by_rotation[k]).all() == np.isnan(by_position[k]).all() for k in by_rotation
    )
    # a direction read where it is defined in one computation and not yet in the other (the
    # arm at the edge of 30° elevation, the elbow at the edge of 30°) is compared where both are
    worst = {k: float(np.nanmax(np.abs(by_rotation[k] - by_position[k]), initial=0.0))
             for k in by_rotation}  # fmt: skip
    assert max(worst.values()) < 3.0, worst
    assert all(np.isfinite(by_rotation[k]).all() for k in ALWAYS_DEFINED if k in by_rotation)


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
    from analysis.pipeline.clinical_stage import repetition_angles
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


# --- Known angles on any rig ---------------------------------------------------------------
# A rig is posed by the world rotation of each segment on top of its anatomical pose: trunk
# upright as in the rest pose, each limb segment turned (shortest arc) from its rest direction to
# hang straight down, the foot keeping its rest angle to the shank. The person faces +z, left is
# +x, y is up. Segments: (proximal joint, distal joint) per rig, written out by hand so the poser
# does not lean on the joint finding under test.
SEGMENTS = ("thigh", "shank", "foot", "upper_arm", "forearm")
RIGS = {
    "kinect-synthetic": (
        None, "Waist", "Spine",
        {"thigh": ("UpperLeg", "LowerLeg"), "shank": ("LowerLeg", "Foot"),
         "foot": ("Foot", "Toes"), "upper_arm": ("UpperArm", "Forearm"),
         "forearm": ("Forearm", "Hand")},
    ),
    "ui-prmd": (
        UI_PRMD / "m01_s01_correct.bvh.gz", "Waist", "Spine",
        {"thigh": ("UpperLeg", "LowerLeg"), "shank": ("LowerLeg", "Foot"),
         "foot": ("Foot", "Toes"), "upper_arm": ("UpperArm", "Forearm"),
         "forearm": ("Forearm", "Hand")},
    ),
    "cmu": (
        DATA / "rigs" / "assimp_01_01.bvh", "Hips", "LowerBack",
        {"thigh": ("UpLeg", "Leg"), "shank": ("Leg", "Foot"), "foot": ("Foot", "ToeBase"),
         "upper_arm": ("Arm", "ForeArm"), "forearm": ("ForeArm", "Hand")},
    ),
    # CMU's "3dsMax-friendly" conversion: LeftShoulder is the upper arm, ZXY and ZYX in one file.
    "cmu-3dsmax": (
        DATA / "rigs" / "bvh11_131_01.bvh", "Hips", "lowerback",
        {"thigh": ("Hip", "Knee"), "shank": ("Knee", "Ankle"), "foot": ("Ankle", "Toe"),
         "upper_arm": ("Shoulder", "Elbow"), "forearm": ("Elbow", "Wrist")},
    ),
}  # fmt: skip
SIGN = {"left": 1.0, "right": -1.0}  # abduction of the left side turns about +z, the right's -z


def rig(name: str) -> tuple[Skeleton, dict[str, str]]:
    """The skeleton and segment -> joint name of its proximal end ("thigh_left": "LeftUpLeg")."""
    path, pelvis, trunk, parts = RIGS[name]
    from tests.synthetic_poses import skeleton as synthetic

    sk = synthetic() if path is None else read(path).skeleton
    joints = {"pelvis": pelvis, "trunk": trunk}
    ends = {}
    for side in ("left", "right"):
        for seg, (a, b) in parts.items():
            joints[f"{seg}_{side}"] = side.capitalize() + a
            ends[f"{seg}_{side}"] = side.capitalize() + b
    assert set(joints.values()) | set(ends.values()) <= set(sk.names)
    return sk, {**joints, **{f"{k}:end": v for k, v in ends.items()}}


def rest_points(sk: Skeleton) -> np.ndarray:
    points = np.zeros((len(sk.names), 3))
    for j, parent in enumerate(sk.parents):
        points[j] = sk.offsets[j] + (points[parent] if parent >= 0 else 0.0)
    return points


def shortest_arc(v: np.ndarray, target: np.ndarray) -> np.ndarray:
    v, target = v / np.linalg.norm(v), target / np.linalg.norm(target)
    axis = np.cross(v, target)
    angle = np.arctan2(np.linalg.norm(axis), v @ target)
    if np.linalg.norm(axis) < 1e-12:
        return np.eye(3)
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle).as_matrix()


def dorsiflexion(sk: Skeleton, roles: dict[str, str], side: str, degrees: float) -> np.ndarray:
    """Turn of the foot in the plane of shank and foot, toes towards the shin."""
    rest = rest_points(sk)
    at = {n: i for i, n in enumerate(sk.names)}
    shank = rest[at[roles[f"shank_{side}:end"]]] - rest[at[roles[f"shank_{side}"]]]
    foot = rest[at[roles[f"foot_{side}:end"]]] - rest[at[roles[f"foot_{side}"]]]
    hang = shortest_arc(shank, np.array([0.0, -1.0, 0.0]))
    axis = np.cross(hang @ foot, [0.0, 1.0, 0.0])
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * np.radians(degrees)).as_matrix()


def world_rotations(sk: Skeleton, roles: dict[str, str], pose: dict, heading: float) -> list:
    """Global rotation of every joint: heading @ pose @ anatomical alignment, both inherited
    down the tree where a joint is not a segment's proximal end."""
    segment_of = {roles[k]: k for k in roles if not k.endswith(":end")}
    rest = rest_points(sk)
    at = {n: i for i, n in enumerate(sk.names)}
    turn = Rotation.from_euler("y", heading, degrees=True).as_matrix()
    posed, aligned, world = [], [], []
    for j, parent in enumerate(sk.parents):
        seg = segment_of.get(sk.names[j])
        p = pose.get(seg, posed[parent] if parent >= 0 else np.eye(3))
        a = aligned[parent] if parent >= 0 else np.eye(3)
        if seg is not None and seg.split("_")[0] in ("thigh", "shank", "upper", "forearm"):
            end = rest[at[roles[f"{seg}:end"]]] - rest[j]
            a = shortest_arc(end, np.array([0.0, -1.0, 0.0]))
        posed.append(p)
        aligned.append(a)
        world.append(turn @ p @ a)
    return world


def channels_of(sk: Skeleton, world: list) -> np.ndarray:
    """One frame of BVH channels (each joint's own rotation order) for these global rotations."""
    row = []
    for j, parent in enumerate(sk.parents):
        local = world[j] if parent < 0 else world[parent].T @ world[j]
        order = "".join(c[0] for c in sk.channels[j] if c.endswith("rotation"))
        euler = dict(
            zip(order, Rotation.from_matrix(local).as_euler(order, degrees=True), strict=True)
        )
        for channel in sk.channels[j]:
            row.append(euler[channel[0]] if channel.endswith("rotation") else 0.0)
    return np.array(row)


def posed_on(rig_name: str, pose_of, heading: float = 0.0) -> dict[str, float]:
    sk, roles = rig(rig_name)
    pose = pose_of(sk, roles)
    row = channels_of(sk, world_rotations(sk, roles, pose, heading))
    series = angle_series(Motion(sk, row[None, :], 1 / 30))
    return {k: float(v[0]) for k, v in series.items()}


def _turn(axis: str, degrees: float):
    return lambda seg: lambda sk, roles: {seg: rot(axis, degrees)}


def known_poses():
    """(angle, expected degrees, pose builder): each movement alone, in its own plane."""
    cases = [
        ("trunk_flexion", 30.0, _turn("x", 30.0)("trunk")),
        ("trunk_lateral_flexion", 20.0, _turn("z", 20.0)("trunk")),  # to the right (−x)
    ]
    for side, s in SIGN.items():
        cases += [
            (f"knee_flexion_{side}", 90.0, _turn("x", 90.0)(f"shank_{side}")),
            (f"hip_flexion_{side}", 60.0, _turn("x", -60.0)(f"thigh_{side}")),
            (f"hip_abduction_{side}", 30.0, _turn("z", s * 30.0)(f"thigh_{side}")),
            (f"shoulder_flexion_{side}", 90.0, _turn("x", -90.0)(f"upper_arm_{side}")),
            (f"shoulder_abduction_{side}", 120.0, _turn("z", s * 120.0)(f"upper_arm_{side}")),
            (f"elbow_flexion_{side}", 90.0, _turn("x", -90.0)(f"forearm_{side}")),
            (
                f"ankle_dorsiflexion_{side}", 15.0,
                lambda sk, roles, side=side: {f"foot_{side}": dorsiflexion(sk, roles, side, 15.0)},
            ),
        ]  # fmt: skip
    return cases


KNOWN_ON_RIGS = known_poses()


@pytest.mark.parametrize("rig_name", list(RIGS))
def test_anatomical_pose_of_every_rig_reads_zero(rig_name):
    angles = posed_on(rig_name, lambda sk, roles: {})
    assert set(angles) == set(ALWAYS_DEFINED)
    assert all(abs(v) < 1e-6 for v in angles.values()), angles


@pytest.mark.parametrize(
    ("name", "expected", "pose_of"), KNOWN_ON_RIGS, ids=[k[0] for k in KNOWN_ON_RIGS]
)
@pytest.mark.parametrize("heading", [0.0, -110.0])
@pytest.mark.parametrize("rig_name", list(RIGS))
def test_each_angle_alone_within_one_degree_on_every_rig(
    rig_name, heading, name, expected, pose_of
):
    angles = posed_on(rig_name, pose_of, heading)
    assert angles[name] == pytest.approx(expected, abs=1.0)
    elevation = name.replace("flexion", "elevation").replace("abduction", "elevation")
    if name.startswith("shoulder_"):  # the arm's angle to the trunk, whatever its plane
        assert angles[elevation] == pytest.approx(expected, abs=1.0)
    # the direction the arm is raised in is where it went, not how far
    moved_too = {n for n in angles if n not in (name, elevation) and abs(angles[n]) >= 1.0
                 and not n.startswith("shoulder_plane_of_elevation")}  # fmt: skip
    assert not moved_too, {n: round(angles[n], 2) for n in moved_too}  # one plane, one angle


@pytest.mark.parametrize("rig_name", list(RIGS))
def test_opposite_movements_are_negative_on_every_rig(rig_name):
    pose = lambda seg, axis, deg: lambda sk, roles: {seg: rot(axis, deg)}  # noqa: E731
    assert posed_on(rig_name, pose("thigh_right", "x", 20.0))["hip_flexion_right"] == (
        pytest.approx(-20.0, abs=1.0)
    )
    assert posed_on(rig_name, pose("thigh_left", "z", -10.0))["hip_abduction_left"] == (
        pytest.approx(-10.0, abs=1.0)
    )
    assert posed_on(rig_name, pose("trunk", "x", -10.0))["trunk_flexion"] == pytest.approx(
        -10.0, abs=1.0
    )
    plantar = posed_on(
        rig_name, lambda sk, roles: {"foot_left": dorsiflexion(sk, roles, "left", -30.0)}
    )
    assert plantar["ankle_dorsiflexion_left"] == pytest.approx(-30.0, abs=1.0)


DEEP_SQUATS = sorted(UI_PRMD.glob("m01_*.bvh.gz"))


def test_the_repository_holds_the_ui_prmd_deep_squats():
    assert len(DEEP_SQUATS) == 14  # subjects s01–s07, correct and incorrect (README.md there)


@pytest.mark.parametrize("path", DEEP_SQUATS, ids=[p.name.split(".")[0] for p in DEEP_SQUATS])
def test_deep_squat_knee_flexion_range_agrees_with_positions_within_5_degrees(path):
    motion = read(path)
    by_rotation = clinical_angles(motion)
    by_position = angle_ranges(angle_series(motion, method="positions"))
    for side in ("left", "right"):
        name = f"knee_flexion_{side}"
        assert by_rotation[name].range > 60.0  # a squat bends the knees
        assert abs(by_rotation[name].range - by_position[name].range) < 5.0
        assert abs(by_rotation[name].max - by_position[name].max) < 5.0


def arm_towards(side: str, elevation: float, plane: float):
    """Pose the upper arm raised ``elevation`` degrees from hanging, in the vertical plane
    ``plane`` degrees from the frontal plane towards the front (0: straight out to the side,
    90: straight forward, −90: backward); shortest arc from hanging, so no roll."""
    lateral = np.array([SIGN[side], 0.0, 0.0])  # the person faces +z, left is +x
    forward = np.array([0.0, 0.0, 1.0])
    e, p = np.radians(elevation), np.radians(plane)
    target = np.sin(e) * (np.cos(p) * lateral + np.sin(p) * forward) - np.cos(e) * np.array(
        [0.0, 1.0, 0.0]
    )
    turn = shortest_arc(np.array([0.0, -1.0, 0.0]), target)
    return lambda sk, roles: {f"upper_arm_{side}": turn}


# (elevation, plane of elevation) -> (flexion, abduction) as a goniometer reads them (issue 26:
# before, each was the elevation times its plane's share, so a diagonal arm at 90° read 63.6°
# in both and an overhead V read 128° abduction): the elevation within 45° of the movement's
# plane, fading linearly to 0 at 90° from it (analysis.clinical.angles.shoulder_angles).
ARM_DIRECTIONS = [
    (90.0, 90.0, 90.0, 0.0),  # forward, horizontal: all flexion, no abduction
    (150.0, 90.0, 150.0, 0.0),  # forward and up
    (90.0, 45.0, 90.0, 90.0),  # diagonally forward and out (scapular-ish plane): its elevation
    (135.0, 45.0, 135.0, 135.0),  # the same diagonal, above the head
    (130.0, 10.0, 28.89, 130.0),  # UI-PRMD deep-squat arms: overhead V, a little forward
    (120.0, 30.0, 80.0, 120.0),  # scaption: abduction reads the elevation
    (60.0, 70.0, 60.0, 26.67),  # mostly forward: flexion reads it, abduction fades
    (40.0, -90.0, -40.0, 0.0),  # backward: extension
    (175.0, 0.0, 116.67, 175.0),  # nearly straight up out to the side: flexion nears it too
]


@pytest.mark.filterwarnings("ignore:Gimbal lock")  # the poser's Euler angles; still exact
@pytest.mark.parametrize(
    "case", ARM_DIRECTIONS, ids=[f"{c[0]:g}-in-{c[1]:g}" for c in ARM_DIRECTIONS]
)
@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("heading", [0.0, -110.0])
@pytest.mark.parametrize("rig_name", list(RIGS))
def test_arm_in_any_plane_reads_its_elevation_as_a_goniometer(rig_name, heading, side, case):
    elevation, plane, flexion, abduction = case
    angles = posed_on(rig_name, arm_towards(side, elevation, plane), heading)
    assert angles[f"shoulder_flexion_{side}"] == pytest.approx(flexion, abs=TOL)
    assert angles[f"shoulder_abduction_{side}"] == pytest.approx(abduction, abs=TOL)
    assert angles[f"shoulder_elevation_{side}"] == pytest.approx(elevation, abs=TOL)
    others = {n: v for n, v in angles.items() if not n.startswith("shoulder_") and abs(v) >= TOL}
    assert not others, others


def _arm_frames(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Per frame: is either wrist above the top of the head (positions), and both
    shoulder abductions (orientations)."""
    from analysis.kinematics import positions

    motion = read(path)
    at = {n: i for i, n in enumerate(motion.skeleton.names)}
    pos = positions(motion)
    above = np.stack(
        [pos[:, at[f"{s}Hand"], 1] > pos[:, at["HeadTip"], 1] for s in ("Left", "Right")]
    )
    series = angle_series(motion)
    return above, np.stack([series[f"shoulder_abduction_{s}"] for s in ("left", "right")])


@pytest.mark.parametrize("subject", ["s01", "s04", "s07"])
def test_ui_prmd_deep_squat_arms_are_really_raised_overhead(subject):
    # The large shoulder abduction on UI-PRMD squats is the subjects' posture (arms held up in
    # a V, wrists above the head), not a rest-pose or projection artefact.
    above, abduction = _arm_frames(UI_PRMD / f"m01_{subject}_correct.bvh.gz")
    assert above.mean() > 0.95
    assert np.all((np.median(abduction, axis=1) > 100) & (np.median(abduction, axis=1) < 160))


def test_ui_prmd_shoulder_abduction_exercise_moves_one_arm_from_hanging():
    _, abduction = _arm_frames(UI_PRMD / "m07_s01_correct.bvh.gz")
    low, high = np.percentile(abduction, [5, 95], axis=1)
    assert np.all(low < 25)  # both arms hang between repetitions
    assert high.min() < 25  # one arm stays down
    assert high.max() > 110  # the other is abducted above the shoulder


# The upper arm's axial rotation (internal +) and the direction it is raised in, ISB's globe:
# (pose, angle, expected degrees). Axes of these poses: x to the body's left, y up, z forward.
FOREARM_FORWARD = {
    "left": rot("x", -90.0) @ rot("z", -90.0),
    "right": rot("x", -90.0) @ rot("z", 90.0),
}
GLOBE = [
    ({"LeftForearm": FOREARM_FORWARD["left"]}, "shoulder_rotation_left", 0.0),
    ({"LeftForearm": rot("y", -45.0) @ FOREARM_FORWARD["left"]}, "shoulder_rotation_left", 45.0),
    ({"LeftForearm": rot("y", 30.0) @ FOREARM_FORWARD["left"]}, "shoulder_rotation_left", -30.0),
    ({"RightForearm": rot("y", 45.0) @ FOREARM_FORWARD["right"]}, "shoulder_rotation_right", 45.0),
    (
        {"RightForearm": rot("y", -60.0) @ FOREARM_FORWARD["right"]},
        "shoulder_rotation_right",
        -60.0,
    ),
    # 90/90: the arm out to the side, the forearm forward (neutral) or up (outward 90°)
    (
        {"LeftUpperArm": rot("z", 0.0), "LeftForearm": rot("y", -90.0)},
        "shoulder_rotation_left",
        0.0,
    ),
    (
        {"LeftUpperArm": rot("z", 0.0), "LeftForearm": rot("z", 90.0)},
        "shoulder_rotation_left",
        -90.0,
    ),
    ({"LeftUpperArm": rot("z", 0.0)}, "shoulder_plane_of_elevation_left", 0.0),
    ({"LeftUpperArm": rot("y", -90.0)}, "shoulder_plane_of_elevation_left", 90.0),
    ({"RightUpperArm": rot("y", 90.0)}, "shoulder_plane_of_elevation_right", 90.0),
    ({"LeftUpperArm": rot("y", -135.0)}, "shoulder_plane_of_elevation_left", 135.0),  # across
    ({"LeftUpperArm": rot("y", 30.0)}, "shoulder_plane_of_elevation_left", -30.0),  # behind
]


@pytest.mark.parametrize(("pose", "name", "expected"), GLOBE, ids=[f"{g[1]}={g[2]}" for g in GLOBE])
@pytest.mark.parametrize("heading", [0.0, 135.0])
def test_shoulder_rotation_and_plane_of_elevation(pose, name, expected, heading):
    assert at(pose, heading)[name] == pytest.approx(expected, abs=TOL)


def test_rotation_and_plane_are_not_measured_where_undefined():
    """A straight elbow gives the upper arm's roll no direction, a hanging arm no plane: they are
    absent, each with its reason in plain words."""
    motion = posed([{"Waist": rot("y", 0.0), "LeftUpperArm": rot("z", -90.0),
                     "RightUpperArm": rot("z", 90.0)}])  # fmt: skip
    measured = measure(motion)
    for side in ("left", "right"):
        assert f"shoulder_rotation_{side}" not in measured.series
        assert "elbow stayed nearly straight" in measured.notes[f"shoulder_rotation_{side}"]
        assert "not raised far enough" in measured.notes[f"shoulder_plane_of_elevation_{side}"]


def test_internal_rotation_on_ui_prmd_shoulder_rotation_exercise():
    """UI-PRMD m09 turns the arm about itself with the elbow bent: its rotation range is wide,
    and the arm's elevation hardly changes."""
    angles = clinical_angles(read(UI_PRMD / "m09_s01_correct.bvh.gz"))
    assert angles["shoulder_rotation_right"].range > 90
    assert angles["shoulder_elevation_right"].range < 45
