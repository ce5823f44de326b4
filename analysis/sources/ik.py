"""Inverse kinematics: joint positions of any capture source → a `Motion` with rotations.

The skeleton is fixed (``JOINTS``): hips (root), spine, chest, neck, head, and on each side upper
arm, forearm, hand, upper leg, lower leg and foot, named as `analysis.bvh.rigs` recognises them, so
`analysis.kinematics.map_onto` puts the result on any exercise's skeleton like another BVH rig.

- Points (canonical names such as ``left_knee``) come in metres, any right-handed axes; a point
  missing in some frames is bridged by linear interpolation (reported); the spine, chest and neck
  are estimated from their neighbours when a source has no such point: the chest is a keypoint
  set's neck, or lies between the shoulders under the head; a missing pelvis lies behind the hip
  joints (`pelvis_behind_hips`), where rigs put the spine's base.
- Bone lengths are the median distances over the take. The rest pose is a person standing
  (Y up, facing +Z, left +X, arms and legs hanging, feet forward), so a standing frame gives
  rotations near zero at the hips, knees and shoulders.
- The hips, spine and chest get full frames from their bone and a second axis: the line between
  the hip joints for the hips, between the shoulders for spine and chest. Limb segments, neck and
  head turn from their parent by the smallest rotation that lands their bone (positions alone do
  not show a limb's twist about its own axis). Where the offset of a branch (hip joint from the
  hips, shoulder from the chest) is measured, its median in the parent's frame is the rest offset,
  so a rigid trunk reads as it is.
- Rotations are made sign-continuous over time (no flips). Smoothing is asked for by the caller
  (``smoothing`` frames, a moving average of the quaternions): off for files, whose recorders
  filter already (a 3-frame average flattens the peaks of a clean take by up to 10° at the
  ankles); on for landmarks a video estimator finds frame by frame.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from analysis.bvh.io import Motion, Skeleton
from analysis.kinematics import quaternions as quat
from analysis.kinematics.retarget import min_rotation
from analysis.sources.errors import CaptureFileError

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
UNITS_PER_METRE = 100.0  # the Motion is written in centimetres, like most BVH files
UP, LEFT, FORWARD = np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0, 1])
DOWN = -UP
CHANNELS_ROOT = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
CHANNELS = ("Zrotation", "Xrotation", "Yrotation")
EULER_ORDER = "ZXY"

# (joint name, parent name, its point, the point its bone runs to, rest direction of that bone),
# depth first as a BVH file lists them (arms, then legs): an import and its BVH export are then
# the same skeleton, joint for joint, and analyse alike.
JOINTS: tuple[tuple[str, str | None, str, str, FloatArray], ...] = (
    ("Hips", None, "pelvis", "chest", UP),
    ("Spine", "Hips", "spine", "chest", UP),
    ("Chest", "Spine", "chest", "neck", UP),
    ("Neck", "Chest", "neck", "head", UP),
    ("Head", "Neck", "head", "head_top", UP),
    *(
        row
        for side in ("left", "right")
        for row in (
            (f"{side.title()}UpperArm", "Chest", f"{side}_shoulder", f"{side}_elbow", DOWN),
            (f"{side.title()}Forearm", f"{side.title()}UpperArm", f"{side}_elbow",
             f"{side}_wrist", DOWN),
            (f"{side.title()}Hand", f"{side.title()}Forearm", f"{side}_wrist",
             f"{side}_hand_tip", DOWN),
        )
    ),
    *(
        row
        for side in ("left", "right")
        for row in (
            (f"{side.title()}UpperLeg", "Hips", f"{side}_hip", f"{side}_knee", DOWN),
            (f"{side.title()}LowerLeg", f"{side.title()}UpperLeg", f"{side}_knee",
             f"{side}_ankle", DOWN),
            (f"{side.title()}Foot", f"{side.title()}LowerLeg", f"{side}_ankle", f"{side}_toe",
             FORWARD),
        )
    ),
)  # fmt: skip
NAMES = tuple(j[0] for j in JOINTS)
PARENTS = tuple(-1 if j[1] is None else NAMES.index(j[1]) for j in JOINTS)
# Joints whose frame has a second axis (the rest are turned from their parent).
FRAMED = {"Hips", "Spine", "Chest"}
REQUIRED = (
    "head", *(f"{s}_{p}" for s in ("left", "right")
              for p in ("shoulder", "elbow", "wrist", "hip", "knee", "ankle")),
)  # fmt: skip
PLAIN = {name: name.replace("_", " ") for name in REQUIRED}


@dataclass(frozen=True, eq=False)
class Solved:
    """The motion and, per canonical point, the number of frames bridged by interpolation;
    ``lost``: per shoulder (``left_shoulder``), the frames where it was lost (`lost_shoulders`),
    only for a shoulder lost somewhere."""

    motion: Motion
    bridged: Mapping[str, int]
    estimated: tuple[str, ...]
    lost: Mapping[str, BoolArray] = field(default_factory=dict)


def bridge(track: FloatArray) -> tuple[FloatArray | None, int]:
    """Fill frames without a position (NaN) by linear interpolation between the nearest frames
    that have one (held at the ends); None when fewer than half the frames have one."""
    ok = np.all(np.isfinite(track), axis=1)
    if ok.sum() < max(2, track.shape[0] // 2):
        return None, 0
    if ok.all():
        return track, 0
    t = np.arange(track.shape[0])
    filled = np.stack([np.interp(t, t[ok], track[ok, k]) for k in range(3)], axis=1)
    return filled, int((~ok).sum())


def usable_points(points: Mapping[str, FloatArray]) -> tuple[dict[str, FloatArray], dict[str, int]]:
    """Bridged tracks of the points with enough frames, and how many frames each needed."""
    out: dict[str, FloatArray] = {}
    bridged: dict[str, int] = {}
    for name, track in points.items():
        filled, gaps = bridge(np.asarray(track, dtype=np.float64))
        if filled is not None:
            out[name] = filled
            if gaps:
                bridged[name] = gaps
    return out, bridged


def complete(points: dict[str, FloatArray]) -> tuple[str, ...]:
    """Estimate the trunk points a source lacks from their neighbours; names what was estimated."""
    missing = [PLAIN[n] for n in REQUIRED if n not in points]
    if missing:
        raise CaptureFileError(
            "The file has no usable positions for the " + ", ".join(missing) + "."
        )
    estimated = []
    if "chest" not in points:
        # A keypoint set's neck (BODY_25, HALPE) is the base of the neck between the shoulders:
        # where a rig's thoracic spine ends. Without it, between the shoulders under the head.
        if "neck" in points:
            points["chest"] = points.pop("neck")
        else:
            points["chest"] = chest_under_head(points)
        estimated.append("chest")
    if "pelvis" not in points:
        points["pelvis"] = pelvis_behind_hips(points)
        estimated.append("pelvis")
    mid = {"spine": ("pelvis", "chest", 0.5), "neck": ("chest", "head", 0.35)}
    for name, (a, b, share) in mid.items():
        if name not in points:
            points[name] = points[a] + share * (points[b] - points[a])
            estimated.append(name)
    return tuple(estimated)


def chest_under_head(points: Mapping[str, FloatArray]) -> FloatArray:
    """The thoracic spine's top of a source without one: between the shoulders, moved along the
    shoulder line to where the head sits over it over the take (the median), since the spine
    runs under the head while the shoulders may stand unevenly about it (one further out)."""
    left, right = points["left_shoulder"], points["right_shoulder"]
    middle = (left + right) / 2
    lateral = _unit(left - right)
    aside = float(np.median(np.sum((points["head"] - middle) * lateral, axis=-1)))
    return middle + aside * lateral


# The spine's base (the lumbosacral joint, a rig's hips joint) lies behind the hip joint centres:
# 0.2 to 0.3 of the distance between them in the UI-PRMD and CMU rigs (medians over a take); the
# trunk line from the middle of the hip joints instead leans forward by several degrees. 0.15
# agreed best with the BVH over the UI-PRMD round trip (`make capture-check`: 0.1 to 0.25 tried),
# the trunk bending forward over the hips moving "behind" with it.
PELVIS_BACK = 0.15


def pelvis_behind_hips(points: Mapping[str, FloatArray]) -> FloatArray:
    """The spine's base of a source without one: ``PELVIS_BACK`` hip widths behind the middle of
    the hip joints, "behind" taken from the hip line and the trunk's line up to the chest."""
    left, right = points["left_hip"], points["right_hip"]
    middle = (left + right) / 2
    lateral = _unit(left - right)
    up = points["chest"] - middle
    up = _unit(up - np.sum(up * lateral, axis=-1, keepdims=True) * lateral)
    forward = np.cross(lateral, up)  # left × up: the body's front (LEFT × UP = FORWARD)
    width = np.linalg.norm(left - right, axis=-1, keepdims=True)
    return middle - PELVIS_BACK * width * forward


def _unit(v: FloatArray) -> FloatArray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9)


def frame_rotation(
    primary: FloatArray, secondary: FloatArray, rest_primary: FloatArray, rest_secondary: FloatArray
) -> FloatArray:
    """Rotations (T, 3, 3) taking the rest pair of axes onto the measured pair (Gram–Schmidt)."""

    def basis(a: FloatArray, b: FloatArray) -> FloatArray:
        e1 = _unit(a)
        e2 = _unit(b - np.sum(b * e1, axis=-1, keepdims=True) * e1)
        return np.stack((e1, e2, np.cross(e1, e2)), axis=-1)

    measured = basis(primary, secondary)
    rest = basis(rest_primary[None], rest_secondary[None])
    return measured @ np.swapaxes(rest, -1, -2)  # fmt: skip


MIN_BONE = 1.0  # centimetres: a shorter "bone" (two points at one place) gives no direction
# Points a trunk segment's bone may run to, nearest first: some rigs put the neck where the chest
# is (CMU conversions), so the next point up gives the direction.
TRUNK_TARGETS = {"Spine": ("chest", "neck", "head"), "Chest": ("neck", "head")}


def _has_length(points: Mapping[str, FloatArray], a: str, b: str) -> bool:
    if a not in points or b not in points:
        return False
    return float(np.median(np.linalg.norm(points[b] - points[a], axis=1))) > MIN_BONE


def global_rotations(points: Mapping[str, FloatArray], rest_dirs: FloatArray) -> FloatArray:
    """Each joint's world rotation (T, J, 3, 3); ``rest_dirs`` (J, 3) are the rest bone
    directions (used by the joints turned from their parent). Points in centimetres."""
    n = next(iter(points.values())).shape[0]
    out = np.empty((n, len(JOINTS), 3, 3))
    shoulders = points["left_shoulder"] - points["right_shoulder"]
    hips = points["left_hip"] - points["right_hip"]
    for j, (name, _parent, own, child, _rest) in enumerate(JOINTS):
        if name == "Hips":
            out[:, j] = frame_rotation(hips, points["chest"] - points["pelvis"], LEFT, UP)
        elif name in FRAMED:
            target = next((t for t in TRUNK_TARGETS[name] if _has_length(points, own, t)), child)
            out[:, j] = frame_rotation(points[target] - points[own], shoulders, UP, LEFT)
        else:
            parent = out[:, PARENTS[j]]
            if not _has_length(points, own, child):
                out[:, j] = parent
                continue
            rest_world = np.einsum("tij,j->ti", parent, rest_dirs[j])
            out[:, j] = min_rotation(rest_world, points[child] - points[own]) @ parent
    return out


def rest_offsets(points: Mapping[str, FloatArray], rotations: FloatArray) -> FloatArray:
    """(J, 3) offsets from each joint's parent: medians in the parent's frame for branches off the
    trunk, median bone length along the rest direction for the others."""
    offsets = np.zeros((len(JOINTS), 3))
    for j, (_name, parent, own, _child, _rest) in enumerate(JOINTS):
        if parent is None:
            continue
        p = PARENTS[j]
        parent_point = JOINTS[p][2]
        delta = points[own] - points[parent_point]
        if JOINTS[p][0] in FRAMED:
            local = np.einsum("tji,tj->ti", rotations[:, p], delta)
            offsets[j] = np.median(local, axis=0)
        else:
            offsets[j] = JOINTS[p][4] * float(np.median(np.linalg.norm(delta, axis=1)))
    return offsets


def end_sites(
    points: Mapping[str, FloatArray], offsets: FloatArray
) -> tuple[list[int], FloatArray]:
    """End Sites of the head, hands and feet: the measured tip, or a stand-in (the neck's length
    for the head, 0.3 of the shin for the feet, 0.3 of the forearm for the hands)."""
    parents, ends = [], []
    stand_in = {"Head": ("Neck", 1.0), "LeftHand": ("LeftForearm", 0.3),
                "RightHand": ("RightForearm", 0.3), "LeftFoot": ("LeftLowerLeg", 0.3),
                "RightFoot": ("RightLowerLeg", 0.3)}  # fmt: skip
    for j, (name, _parent, own, child, rest) in enumerate(JOINTS):
        if name not in stand_in:
            continue
        if child in points:
            length = float(np.median(np.linalg.norm(points[child] - points[own], axis=1)))
        else:
            ref, share = stand_in[name]
            length = share * float(np.linalg.norm(offsets[NAMES.index(ref)]))
        parents.append(j)
        ends.append(rest * length)
    return parents, np.array(ends)


def local_quaternions(rotations: FloatArray, smoothing: int = 1) -> FloatArray:
    """Local rotations (T, J, 4), sign-continuous over time, averaged over ``smoothing`` frames
    (1: not smoothed)."""
    world = quat.from_matrix(rotations)
    local = world.copy()
    for j, p in enumerate(PARENTS):
        if p >= 0:
            local[:, j] = quat.multiply(quat.conjugate(world[:, p]), world[:, j])
    local = quat.make_continuous(local, axis=0)
    if smoothing > 1 and local.shape[0] >= smoothing:
        # Sign-continuous quaternions average like vectors over a few frames (then normalised).
        half = smoothing // 2
        padded = np.concatenate((local[:1].repeat(half, 0), local, local[-1:].repeat(half, 0)))
        kernel = np.ones(2 * half + 1) / (2 * half + 1)
        local = np.apply_along_axis(np.convolve, 0, padded, kernel, mode="valid")
    return quat.normalize(local)


def solve(points: Mapping[str, FloatArray], fps: float, smoothing: int = 1) -> Solved:
    """The motion of the canonical ``points`` ({name: (T, 3) metres, NaN where not seen});
    ``smoothing``: frames the rotations are averaged over (1: none)."""
    if not np.isfinite(fps) or not 1.0 <= fps <= 1000.0:
        raise CaptureFileError(f"The file's frame rate ({fps:g} per second) is not usable.")
    usable, bridged = usable_points(points)
    estimated = complete(usable)
    usable = {k: v * UNITS_PER_METRE for k, v in usable.items()}
    n = next(iter(usable.values())).shape[0]
    if n < 2:
        raise CaptureFileError("The file holds fewer than two frames.")
    rest_dirs = np.array([j[4] for j in JOINTS])
    rotations = global_rotations(usable, rest_dirs)
    offsets = rest_offsets(usable, rotations)
    local = local_quaternions(rotations, smoothing)
    euler = quat.to_euler(local, EULER_ORDER)  # (T, J, 3)
    frames = np.concatenate((usable["pelvis"], euler.reshape(n, -1)), axis=1)
    if not np.all(np.isfinite(frames)):
        raise CaptureFileError("The file's positions do not form a body (values out of range).")
    skeleton = standing_skeleton(usable, offsets)
    # a chest estimated from the shoulders carries them by construction: nothing to compare
    lost = {} if "chest" in estimated else lost_shoulders(usable, rotations, offsets)
    return Solved(Motion(skeleton, frames, 1.0 / fps), bridged, estimated, lost)


# A tracked shoulder farther than this share of the shoulder width (the median distance between
# the shoulders) from the place its chest carries it (its rest offset) was lost by the tracker,
# not moved by the shoulder girdle: 0.15 is 5 cm on an adult's 33 cm. On the KERAAL CTK Kinect
# take the shoulders lost while the elbows meet in front of the face sit 9-12 cm off (17 cm
# towards the camera), its other frames within 3 cm (docs/EVALUATION.md).
LOST_SHOULDER_SHARE = 0.15


def lost_shoulders(
    points: Mapping[str, FloatArray], rotations: FloatArray, offsets: FloatArray
) -> dict[str, BoolArray]:
    """Per shoulder lost in some frame, the frames (T,) where it was: the skeleton keeps it at
    its carried place, but the upper arm is pointed from the tracked one, so the shoulder's
    angles there are the tracker's error. Points in centimetres."""
    chest = NAMES.index("Chest")
    between = points["left_shoulder"] - points["right_shoulder"]
    width = float(np.median(np.linalg.norm(between, axis=1)))
    lost: dict[str, BoolArray] = {}
    for side in ("left", "right"):
        delta = points[f"{side}_shoulder"] - points["chest"]
        local = np.einsum("tji,tj->ti", rotations[:, chest], delta)
        away = np.linalg.norm(local - offsets[NAMES.index(f"{side.title()}UpperArm")], axis=1)
        marked = away > LOST_SHOULDER_SHARE * width
        if marked.any():
            lost[f"{side}_shoulder"] = marked
    return lost


def standing_skeleton(points: Mapping[str, FloatArray], offsets: FloatArray) -> Skeleton:
    """The imported body's skeleton: its joints' rest offsets and the end sites the points give
    (the live camera fits the same skeleton to its first complete frame)."""
    end_parents, end_offsets = end_sites(points, offsets)
    return Skeleton(
        names=NAMES,
        parents=np.array(PARENTS, dtype=np.int64),
        offsets=offsets,
        channels=tuple(CHANNELS_ROOT if p < 0 else CHANNELS for p in PARENTS),
        end_site_parents=np.array(end_parents, dtype=np.int64),
        end_site_offsets=end_offsets,
    )
