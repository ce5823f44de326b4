"""The body's joints in any mapped rig, and the segment geometry the clinical angles read.

Joints are found by name through the rows of `analysis.bvh.skeleton_map.SYNONYMS` (UI-PRMD /
Kinect, CMU, Mixamo, Bandai-Namco names), so a rig's own naming never matters. From them:

- the *pelvis* is the bone from the hips' common parent (the pelvis joint) to its first child on
  the way up the spine; its lateral reference is the line from the left to the right hip joint;
- the *thorax* is the longest bone between that child and the base of the neck (so the short
  connector bones some rigs put at the neck are not taken for it); its lateral reference is the
  line between the collar joints (the shoulder joints when a rig has no collars);
- the limb segments are thigh (hip→knee), shank (knee→ankle), foot (ankle→toe), upper arm
  (shoulder→elbow) and forearm (elbow→wrist).

Every segment frame has the ISB axes (Wu et al. 2002, 2005): X anterior, Y superior (the bone's
long axis, primary) and Z to the right, on both sides. Two independent computations give the
same geometry: ``orientation`` applies each segment's global rotation (forward kinematics of the
BVH channels) to its axes in the file's rest pose; ``positions`` builds the frames from the world
positions of the joints alone (the cross-check, and what a positions-only sensor would give).
Anatomical zeros never come from the rest pose (rigs stand in T-, A- or anatomical poses), only
the segments' shapes do.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion, Skeleton
from analysis.bvh.skeleton_map import SYNONYMS, normalise_name
from analysis.kinematics import positions
from analysis.kinematics import quaternions as quat
from analysis.kinematics.forward_kinematics import global_rotations

FloatArray = npt.NDArray[np.float64]
SIDES = ("left", "right")
SIDE_SIGN = {"left": -1.0, "right": 1.0}  # along Z (to the right)
UP = np.array([0.0, 1.0, 0.0])  # BVH files are y-up (analysis.kinematics.UP_AXIS)

# First name of a SYNONYMS row -> the role it plays here.
_ROLE_OF_ROW = {
    "Waist": "pelvis", "Spine": "spine", "Chest": "chest", "Neck": "neck",
    "LeftCollar": "collar_left", "LeftUpperArm": "shoulder_left", "LeftForearm": "elbow_left",
    "LeftHand": "wrist_left", "RightCollar": "collar_right", "RightUpperArm": "shoulder_right",
    "RightForearm": "elbow_right", "RightHand": "wrist_right", "LeftUpperLeg": "hip_left",
    "LeftLowerLeg": "knee_left", "LeftFoot": "ankle_left", "LeftToes": "toe_left",
    "RightUpperLeg": "hip_right", "RightLowerLeg": "knee_right", "RightFoot": "ankle_right",
    "RightToes": "toe_right",
}  # fmt: skip
LIMBS = {
    "thigh": ("hip", "knee"), "shank": ("knee", "ankle"), "foot": ("ankle", "toe"),
    "upper_arm": ("shoulder", "elbow"), "forearm": ("elbow", "wrist"),
}  # fmt: skip


def _role_table() -> dict[str, str]:
    table: dict[str, str] = {}
    for row in SYNONYMS:
        role = _ROLE_OF_ROW.get(row[0])
        for name in row if role else ():
            table.setdefault(normalise_name(name), role)  # type: ignore[arg-type]
    return table


_ROLE_BY_NAME = _role_table()


def find_joints(skeleton: Skeleton) -> dict[str, int]:
    """Joint index of every role the rig has (``"knee_left"`` …); the first joint in file order
    wins, so ``Spine`` is taken before ``Spine1``."""
    found: dict[str, int] = {}
    for index, name in enumerate(skeleton.names):
        role = _ROLE_BY_NAME.get(normalise_name(name))
        if role is not None:
            found.setdefault(role, index)
    return found


def _ancestors(skeleton: Skeleton, joint: int) -> list[int]:
    """The joint and its ancestors up to the root, nearest first."""
    chain = [joint]
    while skeleton.parents[chain[-1]] >= 0:
        chain.append(int(skeleton.parents[chain[-1]]))
    return chain


@dataclass(frozen=True)
class Frame:
    """A segment frame: long axis from ``bone[0]`` to ``bone[1]``, moved by the global rotation
    of ``bone[0]``; lateral reference from ``lateral[0]`` (left) to ``lateral[1]`` (right), moved
    by the rotation of their nearest common ancestor ``lateral_joint``."""

    bone: tuple[int, int]
    lateral: tuple[int, int]
    lateral_joint: int


@dataclass(frozen=True)
class Body:
    """Where the angles' inputs are in one skeleton (indices into ``skeleton.names``)."""

    joints: dict[str, int]
    pelvis: Frame | None
    thorax: Frame | None
    limbs: dict[str, tuple[int, int]] = field(default_factory=dict)  # "thigh_left" -> (a, b)


def _common_ancestor(skeleton: Skeleton, pair: tuple[int, int]) -> int | None:
    right = set(_ancestors(skeleton, pair[1])[1:])
    return next((j for j in _ancestors(skeleton, pair[0])[1:] if j in right), None)


def _trunk_chain(skeleton: Skeleton, joints: dict[str, int]) -> list[int] | None:
    """Joints from the pelvis joint up to the base of the neck, pelvis first."""
    hips = _lateral_pair(joints, "hip")
    pelvis = None if hips is None else _common_ancestor(skeleton, hips)
    top = joints.get("neck", joints.get("chest"))
    if pelvis is None or top is None:
        return None
    chain = _ancestors(skeleton, top)
    return chain[: chain.index(pelvis) + 1][::-1] if pelvis in chain[1:] else None


def _lateral_pair(joints: dict[str, int], part: str) -> tuple[int, int] | None:
    pair = joints.get(f"{part}_left"), joints.get(f"{part}_right")
    return None if pair[0] is None or pair[1] is None else (pair[0], pair[1])


def _frames(skeleton: Skeleton, joints: dict[str, int]) -> tuple[Frame | None, Frame | None]:
    chain = _trunk_chain(skeleton, joints)
    hips = _lateral_pair(joints, "hip")
    if chain is None or hips is None:
        return None, None
    bones = list(itertools.pairwise(chain))
    pelvis = Frame(bones[0], hips, chain[0])
    upper = bones[1:] or bones
    thorax_bone = max(upper, key=lambda b: float(np.linalg.norm(skeleton.offsets[b[1]])))
    lateral = _lateral_pair(joints, "collar") or _lateral_pair(joints, "shoulder")
    moved_by = None if lateral is None else _common_ancestor(skeleton, lateral)
    if lateral is None or moved_by is None:
        return pelvis, None
    return pelvis, Frame(thorax_bone, lateral, moved_by)


def find_body(skeleton: Skeleton) -> Body:
    """The trunk frames and limb segments this skeleton can give."""
    joints = find_joints(skeleton)
    pelvis, thorax = _frames(skeleton, joints)
    limbs = {}
    for side in SIDES:
        for limb, (a, b) in LIMBS.items():
            if f"{a}_{side}" in joints and f"{b}_{side}" in joints:
                limbs[f"{limb}_{side}"] = (joints[f"{a}_{side}"], joints[f"{b}_{side}"])
    return Body(joints, pelvis, thorax, limbs)


def unit(v: FloatArray) -> FloatArray:
    """Unit vectors along the last axis (NaN where a vector has no length)."""
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(norm > 1e-9, v / norm, np.nan)


def make_frame(long_axis: FloatArray, lateral: FloatArray) -> FloatArray:
    """(..., 3, 3) frames, columns X anterior, Y superior (``long_axis``, primary) and Z (the
    ``lateral`` reference made perpendicular to Y); X = Y × Z."""
    y = unit(long_axis)
    z = unit(lateral - np.sum(lateral * y, axis=-1, keepdims=True) * y)
    return np.stack((np.cross(y, z), y, z), axis=-1)


def rest_positions(skeleton: Skeleton) -> FloatArray:
    """World positions of the joints in the file's rest pose (every channel 0): (J, 3)."""
    still = Motion(skeleton, np.zeros((1, skeleton.n_channels)), 1.0)
    return positions(still)[0]


@dataclass(frozen=True)
class Geometry:
    """Per frame: trunk frames (F, 3, 3) and limb long axes (F, 3), unit, proximal → distal."""

    pelvis: FloatArray | None
    thorax: FloatArray | None
    axes: dict[str, FloatArray]
    rest_axes: dict[str, FloatArray]  # the same limb axes in the rest pose: (3,)


def geometry(motion: Motion, method: str = "orientation") -> Geometry:
    """Segment geometry of every frame, from segment orientations or from positions only."""
    if method not in ("orientation", "positions"):
        raise ValueError(f"method must be 'orientation' or 'positions', not {method!r}")
    body = find_body(motion.skeleton)
    rest = rest_positions(motion.skeleton)
    rest_axes = {k: unit(rest[b] - rest[a]) for k, (a, b) in body.limbs.items()}
    if method == "positions":
        pos = positions(motion)
        frames = [None if f is None else _frame_from_points(pos, f) for f in body_frames(body)]
        axes = {k: unit(pos[:, b] - pos[:, a]) for k, (a, b) in body.limbs.items()}
    else:
        rot = quat.to_matrix(global_rotations(motion))
        frames = [
            None if f is None else _frame_from_rotation(rot, rest, f) for f in body_frames(body)
        ]
        axes = {k: unit(rot[:, a] @ (rest[b] - rest[a])) for k, (a, b) in body.limbs.items()}
    return Geometry(frames[0], frames[1], axes, rest_axes)


def body_frames(body: Body) -> tuple[Frame | None, Frame | None]:
    return body.pelvis, body.thorax


def _frame_from_points(pos: FloatArray, frame: Frame) -> FloatArray:
    (a, b), (left, right) = frame.bone, frame.lateral
    return make_frame(pos[:, b] - pos[:, a], pos[:, right] - pos[:, left])


def _frame_from_rotation(rot: FloatArray, rest: FloatArray, frame: Frame) -> FloatArray:
    (a, b), (left, right) = frame.bone, frame.lateral
    long_axis = rot[:, a] @ (rest[b] - rest[a])
    return make_frame(long_axis, rot[:, frame.lateral_joint] @ (rest[right] - rest[left]))
