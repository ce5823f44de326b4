"""The body's joints in any mapped rig, and the segment geometry the clinical angles read.

Joints are found by `analysis.bvh.rigs.identify` (names, chain and rest pose: UI-PRMD / Kinect,
CMU in both its conversions, Mixamo, Xsens, Rokoko …), so a rig's own naming never matters.
Joints at the same rest position as their parent (CMU's ``LowerBack``, ``Neck`` and collars) are
connectors, not segments. From the joints:

- the *pelvis* turns with the hips' common parent (the pelvis joint); its lateral reference is
  the line from the left to the right hip joint;
- the *thorax* is the longest bone between the pelvis and the base of the neck, turning with the
  joint at its lower end; its lateral reference turns with the collars' common parent (the
  shoulders' when the collars are one point);
- the limb segments are thigh (hip→knee), shank (knee→ankle), foot (ankle→toe), upper arm
  (shoulder→elbow) and forearm (elbow→wrist).

Every segment frame has the ISB axes (Wu et al. 2002, 2005): X anterior, Y superior (the long
axis, primary) and Z to the right, on both sides. The trunk's zero is the rest pose's body frame
(upright, facing away from the hip line): rigs stand upright in their rest pose, whatever they do
with the arms. A rig whose rest trunk does not stand within 45° of the vertical (Bandai-Namco's
and Rokoko's every-bone-along-local-x exports) gets its trunk frames from its bones' positions
instead (`trunk_from_points`) and the vertical from the take (`take_vertical`). Limb zeros never
come from the rest pose (T-, A- or anatomical arms), only the segments' directions do. Two
computations give the same geometry: ``orientation`` turns the rest-pose axes by the segments'
global rotations (forward kinematics of the BVH channels); ``positions`` builds the frames from
the joints' world positions alone (the cross-check, and what a positions-only sensor would give).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion, Skeleton
from analysis.bvh.rigs import identify, rest_points
from analysis.bvh.skeleton_map import SYNONYMS, normalise_name
from analysis.kinematics import Kinematics, kinematics
from analysis.kinematics import quaternions as quat

FloatArray = npt.NDArray[np.float64]
SIDES = ("left", "right")
SIDE_SIGN = {"left": -1.0, "right": 1.0}  # along Z (to the right)
UP = np.array([0.0, 1.0, 0.0])  # most BVH files are y-up (analysis.kinematics.UP_AXIS)
Z_UP = np.array([0.0, 0.0, 1.0])  # Blender / MakeHuman / FAIR exports stand along +z

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


# Body part of `analysis.bvh.rigs.identify` -> the role it plays here.
_ROLE_OF_PART = {
    "pelvis": "pelvis", "chest": "chest", "neck": "neck", "collar": "collar",
    "upper_arm": "shoulder", "forearm": "elbow", "hand": "wrist", "upper_leg": "hip",
    "lower_leg": "knee", "foot": "ankle", "toes": "toe",
}  # fmt: skip
EPS = 1e-6  # file units: closer rest points are one point (zero-length connector bones)
# A rest pose whose spine (or shank) leans more than this from the vertical is not a standing
# figure (Rokoko exports lay every bone along its local x): its rest pose gives no zero.
MAX_REST_TILT = np.cos(np.radians(45.0))


def find_joints(skeleton: Skeleton) -> dict[str, int]:
    """Joint index of every role the rig has (``"knee_left"`` …), found by names, chain and rest
    pose with `analysis.bvh.rigs.identify` (Kinect, CMU, Mixamo, Xsens, Rokoko … names); the
    names of `SYNONYMS` rows stand in where it finds nothing. End Sites are not joints here."""
    found: dict[str, int] = {}
    for part, point in identify(skeleton).items():
        side, _, base = part.partition("_")
        role = _ROLE_OF_PART.get(base if side in SIDES else part)
        if role is not None and point < len(skeleton.names):
            found[f"{role}_{side}" if side in SIDES else role] = point
    if found:
        return found
    for index, name in enumerate(skeleton.names):  # a rig identify cannot read: names only
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
    """A trunk segment's frame.

    From orientations: the global rotation of ``joint`` turns the rest pose's vertical (the long
    axis; rigs stand upright in their rest pose, whatever they do with the arms) and the rotation
    of ``lateral_joint``, the nearest common ancestor of the lateral pair, turns the rest line from
    ``lateral[0]`` (left) to ``lateral[1]`` (right). From positions: the lines ``bone[0]`` →
    ``bone[1]`` and left → right, turned back by the rest pose's own tilt of that bone, so both
    computations read 0 in the rest pose even where a rig's spine bones lean."""

    joint: int
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
    up: FloatArray = field(default_factory=lambda: UP)  # the file's vertical
    upright: bool = True  # the rest pose stands along ``up`` (the trunk's zero is its frame)


def _common_ancestor(skeleton: Skeleton, pair: tuple[int, int]) -> int | None:
    right = set(_ancestors(skeleton, pair[1])[1:])
    return next((j for j in _ancestors(skeleton, pair[0])[1:] if j in right), None)


def _trunk_chain(skeleton: Skeleton, joints: dict[str, int]) -> list[int] | None:
    """Joints from the pelvis joint up to the base of the neck, pelvis first, without the
    zero-length connectors some rigs put between them (CMU's ``LowerBack``, ``Neck``). Where the
    spine does not hang below the hips' joint (MakeHuman: legs and spine are siblings under the
    root), the chain starts at the two's common ancestor."""
    hips = _lateral_pair(joints, "hip")
    pelvis = None if hips is None else _common_ancestor(skeleton, hips)
    top = joints.get("neck", joints.get("chest"))
    if pelvis is None or top is None:
        return None
    chain = _ancestors(skeleton, top)
    if pelvis not in chain[1:]:
        pelvis = _common_ancestor(skeleton, (pelvis, top))
        if pelvis is None:
            return None
    rest = rest_positions(skeleton)
    kept = [pelvis]
    for joint in chain[: chain.index(pelvis)][::-1]:
        if np.linalg.norm(rest[joint] - rest[kept[-1]]) > EPS:
            kept.append(joint)
    return kept if len(kept) >= 2 else None


def vertical_of(skeleton: Skeleton, chain: list[int] | None) -> tuple[FloatArray, bool]:
    """The file's vertical and whether its rest pose stands along it. Z-up exporters (Blender,
    MakeHuman, FAIR) stand their rest figure along +z; every other file is y-up, whatever its rest
    pose does: Bandai-Namco's and Rokoko's lay every bone along its local +x."""
    if chain is None:
        return UP, True
    rest = rest_positions(skeleton)
    trunk = unit(rest[chain[-1]] - rest[chain[0]])
    up = Z_UP if trunk @ Z_UP > MAX_REST_TILT else UP
    return up, bool(trunk @ up > MAX_REST_TILT)


def _lateral_pair(joints: dict[str, int], part: str) -> tuple[int, int] | None:
    pair = joints.get(f"{part}_left"), joints.get(f"{part}_right")
    return None if pair[0] is None or pair[1] is None else (pair[0], pair[1])


def _thorax_lateral(skeleton: Skeleton, joints: dict[str, int]) -> tuple[int, int] | None:
    """The collar joints, or the shoulder joints where the collars are one point (CMU)."""
    rest = rest_positions(skeleton)
    for part in ("collar", "shoulder"):
        pair = _lateral_pair(joints, part)
        if pair is not None and np.linalg.norm(rest[pair[1]] - rest[pair[0]]) > EPS:
            return pair
    return None


def _frames(skeleton: Skeleton, joints: dict[str, int]) -> tuple[Frame | None, Frame | None]:
    chain = _trunk_chain(skeleton, joints)
    hips = _lateral_pair(joints, "hip")
    if chain is None or hips is None:
        return None, None
    bones = list(itertools.pairwise(chain))
    pelvis = Frame(chain[0], bones[0], hips, _common_ancestor(skeleton, hips) or chain[0])
    upper = bones[1:] or bones
    rest = rest_positions(skeleton)
    thorax_bone = max(upper, key=lambda b: float(np.linalg.norm(rest[b[1]] - rest[b[0]])))
    lateral = _thorax_lateral(skeleton, joints)
    moved_by = None if lateral is None else _common_ancestor(skeleton, lateral)
    if lateral is None or moved_by is None:
        return pelvis, None
    # The bone turns with the joint just above its lower end (the lower end itself, unless
    # zero-length connectors sit in between).
    joint = int(skeleton.parents[thorax_bone[1]])
    return pelvis, Frame(joint, thorax_bone, lateral, moved_by)


def find_body(skeleton: Skeleton) -> Body:
    """The trunk frames and limb segments this skeleton can give."""
    joints = find_joints(skeleton)
    pelvis, thorax = _frames(skeleton, joints)
    limbs = {}
    for side in SIDES:
        for limb, (a, b) in LIMBS.items():
            if f"{a}_{side}" in joints and f"{b}_{side}" in joints:
                limbs[f"{limb}_{side}"] = (joints[f"{a}_{side}"], joints[f"{b}_{side}"])
    up, upright = vertical_of(skeleton, _trunk_chain(skeleton, joints))
    return Body(joints, pelvis, thorax, limbs, up, upright)


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
    """World positions of the joints in the file's rest pose (every rotation 0, every joint at
    its OFFSET): (J, 3). Not the frame of all-zero channels: where non-root joints have position
    channels (Bandai-Namco) that frame would put every joint at its parent."""
    return rest_points(skeleton)[: len(skeleton.names)]


@dataclass(frozen=True)
class Geometry:
    """Per frame: trunk frames (F, 3, 3) and limb long axes (F, 3), unit, proximal → distal."""

    pelvis: FloatArray | None
    thorax: FloatArray | None
    axes: dict[str, FloatArray]
    rest_axes: dict[str, FloatArray]  # the same limb axes in the rest pose: (3,)
    up: FloatArray = field(default_factory=lambda: UP)  # the file's vertical: (3,)
    upright: bool = True  # whether the rest pose stands (it then gives the ankle's zero)


def geometry(
    motion: Motion,
    method: str = "orientation",
    *,
    kin: Kinematics | None = None,
    body: Body | None = None,
) -> Geometry:
    """Segment geometry of every frame, from segment orientations or from positions only;
    ``kin`` / ``body``: the motion's `kinematics` and `find_body`, when already computed."""
    if method not in ("orientation", "positions"):
        raise ValueError(f"method must be 'orientation' or 'positions', not {method!r}")
    skeleton = motion.skeleton
    body = find_body(skeleton) if body is None else body
    kin = kinematics(motion) if kin is None else kin
    rest = rest_positions(skeleton)
    rest_axes = {k: unit(rest[b] - rest[a]) for k, (a, b) in body.limbs.items()}
    pos = kin.positions
    if not body.upright:  # the rest pose is no posture: trunk frames from the body's own lines
        axes = {k: unit(pos[:, b] - pos[:, a]) for k, (a, b) in body.limbs.items()}
        pelvis, thorax = trunk_from_points(pos, body)
        return Geometry(pelvis, thorax, axes, rest_axes, take_vertical(pos, body), False)
    neutral = neutral_frame(rest, body)
    if method == "positions":
        frames = [
            None if f is None or neutral is None else _frame_from_points(pos, rest, f, neutral)
            for f in body_frames(body)
        ]
        axes = {k: unit(pos[:, b] - pos[:, a]) for k, (a, b) in body.limbs.items()}
    else:
        # matrices of only the joints read: a rig's fingers and toes would double the work
        rot = {j: quat.to_matrix(kin.global_q[:, j]) for j in _turning_joints(skeleton, body)}
        frames = [
            None if f is None or neutral is None else _frame_from_rotation(rot, f, neutral)
            for f in body_frames(body)
        ]
        axes = {
            k: unit(_chain_vector(skeleton, rot, a, b, motion.n_frames))
            for k, (a, b) in body.limbs.items()
        }
    return Geometry(frames[0], frames[1], axes, rest_axes, body.up, True)


def trunk_from_points(pos: FloatArray, body: Body) -> tuple[FloatArray | None, ...]:
    """Trunk frames of a rig whose rest pose is not a standing figure (Bandai-Namco, Rokoko lay
    every bone along its local +x, so turning the rest axes gives no anatomical frame): each
    segment's long axis is its bone (pelvis joint → first spine joint, the thorax bone), its
    lateral axis the hip or collar line. Where the bone's upper joint hangs directly from the
    frame's joint (Bandai-Namco's ``Hips`` → ``Spine``, ``Chest`` → ``Neck``), this is the frame
    the joint's rotation turns."""
    if body.pelvis is None:
        return None, None
    frames = [
        None
        if f is None
        else make_frame(
            pos[:, f.bone[1]] - pos[:, f.bone[0]], pos[:, f.lateral[1]] - pos[:, f.lateral[0]]
        )
        for f in body_frames(body)
    ]
    return frames[0], frames[1]


def take_vertical(pos: FloatArray, body: Body) -> FloatArray:
    """The vertical of a file whose rest pose says nothing about it: +y or +z, whichever the
    pelvis → thorax line follows more over the take (people mostly stand or sit upright)."""
    if body.pelvis is None:
        return body.up
    top = body.thorax.bone[1] if body.thorax is not None else body.pelvis.bone[1]
    trunk = np.nanmean(unit(pos[:, top] - pos[:, body.pelvis.bone[0]]), axis=0)
    return Z_UP if trunk @ Z_UP > trunk @ UP else UP


def body_frames(body: Body) -> tuple[Frame | None, Frame | None]:
    return body.pelvis, body.thorax


def _turning_joints(skeleton: Skeleton, body: Body) -> set[int]:
    """The joints whose global rotation the orientation geometry reads: each trunk frame's
    joints and every joint on the way up from each limb's distal end to its proximal one."""
    out = set()
    for frame in body_frames(body):
        if frame is not None:
            out |= {frame.joint, frame.lateral_joint}
    for a, b in body.limbs.values():
        joint = b
        while joint != a and joint >= 0:
            joint = int(skeleton.parents[joint])
            out.add(joint)
    return {j for j in out if j >= 0}


def _chain_vector(
    skeleton: Skeleton, rot: dict[int, FloatArray], a: int, b: int, n_frames: int
) -> FloatArray:
    """World vector from joint ``a`` to its descendant ``b`` from the global rotations: each
    rest offset on the way turned by its parent's rotation (twist and connector joints between
    the two move the segment too)."""
    total = np.zeros((n_frames, 3))
    joint = b
    while joint != a and joint >= 0:
        parent = int(skeleton.parents[joint])
        total += rot[parent] @ skeleton.offsets[joint] if parent >= 0 else 0.0
        joint = parent
    return total


def neutral_frame(rest: FloatArray, body: Body) -> FloatArray | None:
    """The body's frame in the rest pose, which both trunk segments have at 0: upright, facing
    away from the line between the hip joints (so a rig whose shoulder joints sit a little
    askew, as CMU's, still faces where its hips face)."""
    if body.pelvis is None:
        return None
    left, right = body.pelvis.lateral
    return make_frame(body.up, rest[right] - rest[left])


def _frame_from_points(
    pos: FloatArray, rest: FloatArray, frame: Frame, neutral: FloatArray
) -> FloatArray:
    (a, b), (left, right) = frame.bone, frame.lateral
    now = make_frame(pos[:, b] - pos[:, a], pos[:, right] - pos[:, left])
    at_rest = make_frame(rest[b] - rest[a], rest[right] - rest[left])
    return now @ at_rest.T @ neutral


def _frame_from_rotation(
    rot: dict[int, FloatArray], frame: Frame, neutral: FloatArray
) -> FloatArray:
    return make_frame(rot[frame.joint] @ neutral[:, 1], rot[frame.lateral_joint] @ neutral[:, 2])
