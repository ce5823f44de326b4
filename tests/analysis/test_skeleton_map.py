"""Body parts of the rigs clinics use, found by `analysis.bvh.rigs.identify` from joint names and
the chain; ambiguous words (Shoulder, Ankle/Foot, Hip) settled by structure; sides from geometry
when names give none."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.bvh import Skeleton, SkeletonMismatchError, read
from analysis.bvh.rigs import identify, parse_name
from tests.synthetic_motion import skeleton as synthetic_skeleton

# Per rig: (name, parent) in file order; expected role → name.
ARM_LEG = ("upper_arm", "forearm", "hand", "upper_leg", "lower_leg", "foot")


def build(joints: list[tuple[str, str | None]], offsets: dict[str, tuple] | None = None):
    names = [n for n, _ in joints]
    offsets = offsets or {}
    return Skeleton(
        names=tuple(names),
        parents=np.array([names.index(p) if p else -1 for _, p in joints], dtype=np.int64),
        offsets=np.array([offsets.get(n, (0.0, 1.0, 0.0)) for n in names], dtype=np.float64),
        channels=tuple(("Xrotation",) for _ in names),
        end_site_parents=np.zeros(0, dtype=np.int64),
        end_site_offsets=np.zeros((0, 3)),
    )


def chain(*names: str, parent: str | None = None) -> list[tuple[str, str | None]]:
    out = []
    for name in names:
        out.append((name, parent))
        parent = name
    return out


def both(fmt: str, *parts: str, parent: str, sides=("Left", "Right")) -> list:
    out = []
    for side in sides:
        out += chain(*(fmt.format(side=side, part=p) for p in parts), parent=parent)
    return out


RIGS = {
    "kinect_v2": (
        chain("SpineBase", "SpineMid", "SpineShoulder", "Neck", "Head")
        + both("{part}{side}", "Shoulder", "Elbow", "Wrist", "Hand", "HandTip",
               parent="SpineShoulder")
        + both("{part}{side}", "Hip", "Knee", "Ankle", "Foot", parent="SpineBase"),
        {"pelvis": "SpineBase", "chest": "SpineShoulder", "neck": "Neck", "head": "Head",
         "left_upper_arm": "ShoulderLeft", "left_forearm": "ElbowLeft", "left_hand": "WristLeft",
         "left_upper_leg": "HipLeft", "left_lower_leg": "KneeLeft", "left_foot": "AnkleLeft",
         "left_toes": "FootLeft"},
    ),
    "azure_kinect": (
        chain("PELVIS", "SPINE_NAVAL", "SPINE_CHEST", "NECK", "HEAD", "NOSE")
        + both("{part}_{side}", "CLAVICLE", "SHOULDER", "ELBOW", "WRIST", "HAND",
               parent="SPINE_CHEST", sides=("LEFT", "RIGHT"))
        + both("{part}_{side}", "HIP", "KNEE", "ANKLE", "FOOT", parent="PELVIS",
               sides=("LEFT", "RIGHT")),
        {"pelvis": "PELVIS", "chest": "SPINE_CHEST", "head": "HEAD",
         "left_collar": "CLAVICLE_LEFT",
         "left_upper_arm": "SHOULDER_LEFT", "left_hand": "WRIST_LEFT", "left_foot": "ANKLE_LEFT",
         "left_toes": "FOOT_LEFT"},
    ),
    "xsens_mvn": (
        chain("Pelvis", "L5", "L3", "T12", "T8", "Neck", "Head")
        + both("{side}{part}", "Shoulder", "UpperArm", "ForeArm", "Hand", parent="T8")
        + both("{side}{part}", "UpperLeg", "LowerLeg", "Foot", "Toe", parent="Pelvis"),
        {"pelvis": "Pelvis", "chest": "T8", "neck": "Neck", "left_collar": "LeftShoulder",
         "left_upper_arm": "LeftUpperArm", "left_forearm": "LeftForeArm",
         "left_upper_leg": "LeftUpperLeg", "left_lower_leg": "LeftLowerLeg",
         "left_toes": "LeftToe"},
    ),
    "optitrack": (
        chain("Hip", "Ab", "Chest", "Neck", "Head")
        + both("{side}{part}", "Shoulder", "UArm", "FArm", "Hand", parent="Chest", sides="LR")
        + both("{side}{part}", "Thigh", "Shin", "Foot", "Toe", parent="Hip", sides="LR"),
        {"pelvis": "Hip", "chest": "Chest", "left_collar": "LShoulder", "left_upper_arm": "LUArm",
         "left_forearm": "LFArm", "right_hand": "RHand", "left_upper_leg": "LThigh",
         "left_lower_leg": "LShin", "right_toes": "RToe"},
    ),
    "perception_neuron": (
        chain("Hips", "Spine", "Spine1", "Spine2", "Spine3", "Neck", "Head")
        + both("{side}{part}", "Shoulder", "Arm", "ForeArm", "Hand", "HandThumb1", parent="Spine3")
        + both("{side}{part}", "UpLeg", "Leg", "Foot", parent="Hips"),
        {"pelvis": "Hips", "chest": "Spine3", "left_collar": "LeftShoulder",
         "left_upper_arm": "LeftArm", "left_lower_leg": "LeftLeg", "left_foot": "LeftFoot"},
    ),
    "mixamo": (
        chain("mixamorig:Hips", "mixamorig:Spine", "mixamorig:Spine1", "mixamorig:Spine2",
              "mixamorig:Neck", "mixamorig:Head", "mixamorig:HeadTop_End")
        + both("mixamorig:{side}{part}", "Shoulder", "Arm", "ForeArm", "Hand",
               parent="mixamorig:Spine2")
        + both("mixamorig:{side}{part}", "UpLeg", "Leg", "Foot", "ToeBase", "Toe_End",
               parent="mixamorig:Hips"),
        {"chest": "mixamorig:Spine2", "head_top": "mixamorig:HeadTop_End",
         "left_collar": "mixamorig:LeftShoulder", "left_toes": "mixamorig:LeftToeBase"},
    ),
    "blender_rigify": (
        chain("spine", "spine.001", "spine.002", "spine.003", "spine.004", "spine.005", "spine.006")
        + both("{part}.{side}", "shoulder", "upper_arm", "forearm", "hand", parent="spine.003",
               sides="LR")
        + both("{part}.{side}", "thigh", "shin", "foot", "toe", parent="spine", sides="LR"),
        {"pelvis": "spine", "chest": "spine.003", "head": "spine.006", "left_collar": "shoulder.L",
         "left_upper_arm": "upper_arm.L", "right_lower_leg": "shin.R", "left_toes": "toe.L"},
    ),
    "makehuman_default": (
        chain("root", "spine05", "spine04", "spine03", "spine02", "spine01", "neck01", "neck02",
              "head")
        + both("{part}.{side}", "clavicle", "shoulder01", "upperarm01", "upperarm02",
               "lowerarm01", "lowerarm02", "wrist", parent="spine01", sides="LR")
        + both("{part}.{side}", "pelvis", "upperleg01", "upperleg02", "lowerleg01", "foot",
               "toe1-1", parent="root", sides="LR"),
        {"pelvis": "root", "chest": "spine01", "neck": "neck01", "left_collar": "clavicle.L",
         "left_upper_arm": "upperarm01.L", "left_forearm": "lowerarm01.L", "left_hand": "wrist.L",
         "left_upper_leg": "upperleg01.L", "left_toes": "toe1-1.L"},
    ),
    "3ds_max_biped": (
        chain("Bip01", "Bip01 Pelvis", "Bip01 Spine", "Bip01 Spine1", "Bip01 Neck", "Bip01 Head",
              "Bip01 HeadNub")
        + both("Bip01 {side} {part}", "Clavicle", "UpperArm", "Forearm", "Hand",
               parent="Bip01 Neck", sides="LR")
        + both("Bip01 {side} {part}", "Thigh", "Calf", "Foot", "Toe0", parent="Bip01 Pelvis",
               sides="LR"),
        {"pelvis": "Bip01 Pelvis", "chest": "Bip01 Neck", "head": "Bip01 Head",
         "head_top": "Bip01 HeadNub", "left_lower_leg": "Bip01 L Calf",
         "left_toes": "Bip01 L Toe0"},
    ),
    "video_h36m": (
        chain("Hips", "Spine", "Thorax", "Neck", "Head")
        + both("{side}{part}", "Shoulder", "Elbow", "Wrist", parent="Thorax")
        + both("{side}{part}", "Hip", "Knee", "Ankle", parent="Hips"),
        {"pelvis": "Hips", "chest": "Thorax", "left_upper_arm": "LeftShoulder",
         "left_forearm": "LeftElbow", "left_hand": "LeftWrist", "left_upper_leg": "LeftHip",
         "left_foot": "LeftAnkle"},
    ),
    "cmu_asf": (
        chain("root", "lowerback", "upperback", "thorax", "lowerneck", "upperneck", "head")
        + both("{side}{part}", "clavicle", "humerus", "radius", "wrist", "hand", parent="thorax",
               sides="lr")
        + both("{side}{part}", "hipjoint", "femur", "tibia", "foot", "toes", parent="root",
               sides="lr"),
        {"pelvis": "root", "chest": "thorax", "left_collar": "lclavicle",
         "left_upper_arm": "lhumerus", "left_forearm": "lradius", "left_hand": "lwrist",
         "left_upper_leg": "lfemur", "left_lower_leg": "ltibia", "left_foot": "lfoot"},
    ),
}  # fmt: skip


@pytest.mark.parametrize("rig", sorted(RIGS))
def test_body_parts_of_common_rigs(rig):
    joints, expected = RIGS[rig]
    sk = build(joints)
    roles = identify(sk)
    for side in ("left", "right"):
        for part in ARM_LEG:
            assert f"{side}_{part}" in roles, (rig, side, part)
    assert {"pelvis", "chest", "head"} <= set(roles)
    found = {role: sk.names[roles[role]] for role in expected}
    assert found == expected


@pytest.mark.parametrize(
    ("name", "parsed"),
    [
        ("LeftUpLeg", ("left", "upleg")), ("mixamorig:RightForeArm", ("right", "forearm")),
        ("UpArm_L", ("left", "uparm")), ("KneeLeft", ("left", "knee")),
        ("LUArm", ("left", "uarm")), ("rhand", ("right", "hand")), ("thigh.R", ("right", "thigh")),
        ("Bip01 L Toe0", ("left", "toe")), ("LHipJoint", ("left", "hipjoint")),
        ("Spine1", (None, "spine")), ("lowerback", (None, "lowerback")),
    ],
)  # fmt: skip
def test_names_split_into_side_and_part(name, parsed):
    assert parse_name(name) == parsed


def test_sides_from_the_rest_pose_when_names_give_none():
    # Facing +z with y up: the subject's left is +x.
    joints = [
        *chain("Pelvis", "Chest", "Head"),
        ("Thigh1", "Pelvis"), ("Shin1", "Thigh1"), ("Foot1", "Shin1"), ("Toe1", "Foot1"),
        ("Thigh2", "Pelvis"), ("Shin2", "Thigh2"), ("Foot2", "Shin2"), ("Toe2", "Foot2"),
        ("UpperArm1", "Chest"), ("Forearm1", "UpperArm1"), ("Hand1", "Forearm1"),
        ("UpperArm2", "Chest"), ("Forearm2", "UpperArm2"), ("Hand2", "Forearm2"),
    ]  # fmt: skip
    offsets = {
        "Chest": (0, 40, 0), "Head": (0, 30, 0), "Thigh1": (-9, -5, 0), "Thigh2": (9, -5, 0),
        "Shin1": (0, -40, 0), "Shin2": (0, -40, 0), "Foot1": (0, -40, 0), "Foot2": (0, -40, 0),
        "Toe1": (0, -5, 12), "Toe2": (0, -5, 12), "UpperArm1": (-18, 0, 0), "UpperArm2": (18, 0, 0),
        "Forearm1": (-28, 0, 0), "Forearm2": (28, 0, 0), "Hand1": (-25, 0, 0), "Hand2": (25, 0, 0),
    }  # fmt: skip
    sk = build(joints, offsets)
    roles = identify(sk)
    assert sk.names[roles["left_upper_leg"]] == "Thigh2"
    assert sk.names[roles["right_upper_leg"]] == "Thigh1"
    assert sk.names[roles["left_hand"]] == "Hand2"
    assert sk.names[roles["pelvis"]] == "Pelvis" and sk.names[roles["chest"]] == "Chest"


def test_the_ui_prmd_skeleton_and_the_synthetic_one():
    ui = identify(read("data/ui-prmd/reps/m01_s01_e01.bvh.gz").skeleton)
    assert len(ui) == 21  # every UI-PRMD joint but the spine joint between hips and chest
    synthetic = identify(synthetic_skeleton())
    assert "left_foot" not in synthetic and "left_lower_leg" in synthetic


def test_a_skeleton_without_legs_is_refused_naming_the_parts():
    from analysis.kinematics import map_onto

    tutor = read("data/ui-prmd/reps/m01_s01_e01.bvh.gz")
    upper = build(
        chain("Hips", "Spine", "Chest", "Neck", "Head")
        + both("{side}{part}", "Shoulder", "Arm", "ForeArm", "Hand", parent="Chest")
    )
    from analysis.bvh import Motion

    motion = Motion(upper, np.zeros((3, len(upper.names))), 1 / 30)
    with pytest.raises(SkeletonMismatchError) as caught:
        map_onto(motion, tutor.skeleton)
    text = str(caught.value)
    assert (
        "no joint we recognise as the hips, left thigh, left lower leg, left foot, right thigh, "
        "right lower leg and right foot." in text
    )
    assert "LeftUpLeg" not in text and "LeftUpperLeg" not in text
