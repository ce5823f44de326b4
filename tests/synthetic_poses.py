"""Synthetic rigs posed by world rotations of their segments: known angles for tests and docs.

Rotations are written to BVH channels (``Zrotation Xrotation Yrotation``) with scipy, so the
poses do not depend on the quaternion code of `analysis.kinematics`. The person faces +z, left
is +x, y is up (as in UI-PRMD); the arms are in a T-pose at rest, not the anatomical pose.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from analysis.bvh import Motion, Skeleton
from analysis.clinical.body import FloatArray

# Kinect / UI-PRMD names; MIXAMO renames them.
KINECT = (
    ("Waist", -1, (0.0, 90.0, 0.0)),
    ("Spine", 0, (0.0, 25.0, 0.0)),
    ("Chest", 1, (0.0, 22.0, 0.0)),
    ("Neck", 2, (0.0, 3.0, 0.0)),
    ("Head", 3, (0.0, 12.0, 0.0)),
    ("LeftCollar", 2, (2.0, -1.0, 0.0)),
    ("LeftUpperArm", 5, (15.0, 0.0, 0.0)),
    ("LeftForearm", 6, (28.0, 0.0, 0.0)),
    ("LeftHand", 7, (25.0, 0.0, 0.0)),
    ("RightCollar", 2, (-2.0, -1.0, 0.0)),
    ("RightUpperArm", 9, (-15.0, 0.0, 0.0)),
    ("RightForearm", 10, (-28.0, 0.0, 0.0)),
    ("RightHand", 11, (-25.0, 0.0, 0.0)),
    ("LeftUpperLeg", 0, (8.0, -2.0, 0.0)),
    ("LeftLowerLeg", 13, (0.0, -42.0, 0.0)),
    ("LeftFoot", 14, (0.0, -40.0, 0.0)),
    ("LeftToes", 15, (0.0, -6.0, 14.0)),
    ("RightUpperLeg", 0, (-8.0, -2.0, 0.0)),
    ("RightLowerLeg", 17, (0.0, -42.0, 0.0)),
    ("RightFoot", 18, (0.0, -40.0, 0.0)),
    ("RightToes", 19, (0.0, -6.0, 14.0)),
)
MIXAMO_NAMES = {
    "Waist": "mixamorig:Hips", "Spine": "mixamorig:Spine1", "Chest": "mixamorig:Spine2",
    "Neck": "mixamorig:Neck", "Head": "mixamorig:Head", "LeftCollar": "mixamorig:LeftShoulder",
    "LeftUpperArm": "mixamorig:LeftArm", "LeftForearm": "mixamorig:LeftForeArm",
    "LeftHand": "mixamorig:LeftHand", "RightCollar": "mixamorig:RightShoulder",
    "RightUpperArm": "mixamorig:RightArm", "RightForearm": "mixamorig:RightForeArm",
    "RightHand": "mixamorig:RightHand", "LeftUpperLeg": "mixamorig:LeftUpLeg",
    "LeftLowerLeg": "mixamorig:LeftLeg", "LeftFoot": "mixamorig:LeftFoot",
    "LeftToes": "mixamorig:LeftToeBase", "RightUpperLeg": "mixamorig:RightUpLeg",
    "RightLowerLeg": "mixamorig:RightLeg", "RightFoot": "mixamorig:RightFoot",
    "RightToes": "mixamorig:RightToeBase",
}  # fmt: skip
ROTATION = ("Zrotation", "Xrotation", "Yrotation")


def skeleton(names: Mapping[str, str] | None = None) -> Skeleton:
    rename = names or {}
    ends = [4, 8, 12, 16, 20]
    return Skeleton(
        names=tuple(rename.get(n, n) for n, _, _ in KINECT),
        parents=np.array([p for _, p, _ in KINECT], dtype=np.int64),
        offsets=np.array([o for _, _, o in KINECT], dtype=np.float64),
        channels=tuple(
            ("Xposition", "Yposition", "Zposition", *ROTATION) if p < 0 else ROTATION
            for _, p, _ in KINECT
        ),
        end_site_parents=np.array(ends, dtype=np.int64),
        end_site_offsets=np.tile([0.0, 5.0, 0.0], (len(ends), 1)),
    )


def rot(axis: str, degrees: float) -> FloatArray:
    """World rotation matrix about one axis ('x', 'y', 'z'), right-handed."""
    return np.asarray(Rotation.from_euler(axis, degrees, degrees=True).as_matrix())


# World rotations that hang the T-pose arms down along the body (the anatomical pose).
HANG = {"LeftUpperArm": rot("z", -90.0), "RightUpperArm": rot("z", 90.0)}


def pose_row(sk: Skeleton, world: Mapping[str, FloatArray]) -> FloatArray:
    """One frame row: every joint's world rotation is ``world[name]`` (Kinect names), or its
    parent's when not given; arms hang unless the pose says otherwise."""
    given = {**HANG, **world}
    glob: list[np.ndarray] = []
    row: list[float] = []
    for j, (name, parent, _) in enumerate(KINECT):
        g = given.get(name, glob[parent] if parent >= 0 else np.eye(3))
        glob.append(g)
        local = g if parent < 0 else glob[parent].T @ g
        with warnings.catch_warnings():  # 90° about x is a gimbal lock of ZXY: still exact
            warnings.simplefilter("ignore", UserWarning)
            z, x, y = Rotation.from_matrix(local).as_euler("ZXY", degrees=True)
        row += [*sk.offsets[j], z, x, y] if parent < 0 else [z, x, y]
    return np.array(row)


def posed(
    world_frames: Sequence[Mapping[str, FloatArray]], names: Mapping[str, str] | None = None
) -> Motion:
    """A motion with one frame per pose."""
    sk = skeleton(names)
    return Motion(sk, np.array([pose_row(sk, w) for w in world_frames]), 1 / 30)
