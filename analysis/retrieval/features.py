"""Per-frame body-part distance features for motion retrieval (paper 002, section 3.1).

Takahara et al. describe every frame by 17 distances between body parts, after Müller & Röder's
relational features, instead of the 96 joint angles of the CMU rig: distances do not depend on where
the performer stands or which way they face, and they say directly what the body does (hands up,
knees bent, feet apart). The paper does not list its 17 distances; ours are `FEATURES` below, chosen
to separate the UI-PRMD rehabilitation exercises (squats, lunges, leg raises and arm raises).

Distances are divided by the performer's body size (`body_size`) so that tall and short people
doing the same exercise give the same features.

Joints are found by role (head, left hand, ...). The UI-PRMD rig has an exact map
(`UI_PRMD_JOINTS`); other rigs are matched by common names (LeftHand, HandLeft, L_Hand, hand.L,
mixamorig:LeftHand, WristLeft ...).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from analysis.bvh import RecordingTooShortError, SkeletonMismatchError, normalise_name

SIDED_PARTS = ("shoulder", "elbow", "hand", "hip", "knee", "foot")
ROLES: tuple[str, ...] = (
    "head",
    "neck",
    "root",
    *(f"{side}_{part}" for part in SIDED_PARTS for side in ("l", "r")),
)

UI_PRMD_JOINTS: Mapping[str, str] = {
    "head": "Head",
    "neck": "Neck",
    "root": "Waist",
    "l_shoulder": "LeftUpperArm",
    "r_shoulder": "RightUpperArm",
    "l_elbow": "LeftForearm",
    "r_elbow": "RightForearm",
    "l_hand": "LeftHand",
    "r_hand": "RightHand",
    "l_hip": "LeftUpperLeg",
    "r_hip": "RightUpperLeg",
    "l_knee": "LeftLowerLeg",
    "r_knee": "RightLowerLeg",
    "l_foot": "LeftFoot",
    "r_foot": "RightFoot",
}

# Ordered by preference: rigs such as CMU/Mixamo have both LeftShoulder (the collar bone) and
# LeftArm (the shoulder joint), so "arm" must win over "shoulder"; Kinect says ShoulderLeft.
# Kinect's FootLeft is the toe and AnkleLeft the ankle (UI-PRMD's LeftFoot), so "ankle" goes first.
_PART_ALIASES: Mapping[str, tuple[str, ...]] = {
    "head": ("head",),
    "neck": ("neck", "neck1", "shouldercenter", "spineshoulder"),
    "root": ("hips", "pelvis", "waist", "hipcenter", "spinebase", "root", "hip"),
    "shoulder": ("upperarm", "uparm", "arm", "humerus", "shoulder"),
    "elbow": ("forearm", "lowerarm", "elbow"),
    "hand": ("hand", "wrist"),
    "hip": ("upleg", "upperleg", "thigh", "femur", "hip"),
    "knee": ("lowerleg", "leg", "shin", "calf", "tibia", "knee"),
    "foot": ("ankle", "foot"),
}
_SIDE_WORDS: Mapping[str, tuple[str, ...]] = {"l": ("left", "l"), "r": ("right", "r")}

# (name, role a, role b): the distance between a and b; b = "front" means the signed distance of a
# in front of the body's frontal plane (Müller & Röder's plane features), which tells a forward step
# from a sideways one and an arm raised forward from one raised sideways; plain distances cannot.
# "mid_feet" is the midpoint of the two feet.
FEATURES: tuple[tuple[str, str, str], ...] = (
    ("left hand to head", "l_hand", "head"),
    ("right hand to head", "r_hand", "head"),
    ("hands apart", "l_hand", "r_hand"),
    ("left elbow extension (hand to shoulder)", "l_hand", "l_shoulder"),
    ("right elbow extension (hand to shoulder)", "r_hand", "r_shoulder"),
    ("left arm away from body (elbow to hip)", "l_elbow", "l_hip"),
    ("right arm away from body (elbow to hip)", "r_elbow", "r_hip"),
    ("left hand in front of the body", "l_hand", "front"),
    ("right hand in front of the body", "r_hand", "front"),
    ("feet apart", "l_foot", "r_foot"),
    ("left foot in front of the body", "l_foot", "front"),
    ("right foot in front of the body", "r_foot", "front"),
    ("left knee extension (foot to hip)", "l_foot", "l_hip"),
    ("right knee extension (foot to hip)", "r_foot", "r_hip"),
    ("left hip flexion (knee to neck)", "l_knee", "neck"),
    ("right hip flexion (knee to neck)", "r_knee", "neck"),
    ("body extension (head to between the feet)", "head", "mid_feet"),
)
N_FEATURES = len(FEATURES)


def _mirrored_role(role: str) -> str:
    side, _, part = role.partition("_")
    return {"l": f"r_{part}", "r": f"l_{part}"}.get(side, role) if part else role


def _mirror_order() -> tuple[int, ...]:
    """Column k of a take's mirror image (left and right swapped) is column ``order[k]``."""
    index = {(a, b): k for k, (_, a, b) in enumerate(FEATURES)}
    order = []
    for _, a, b in FEATURES:
        pair = (_mirrored_role(a), _mirrored_role(b))
        order.append(index.get(pair, index.get(pair[::-1], -1)))
    if sorted(order) != list(range(N_FEATURES)):
        raise AssertionError("every feature needs its mirror image among FEATURES")
    return tuple(order)


MIRROR_ORDER = _mirror_order()


def mirrored_features(features: np.ndarray) -> np.ndarray:
    """The (F, 17) features of the same take done with the other side: a lunge led with the
    right leg reads as one led with the left (distances do not change sign when mirrored)."""
    return np.asarray(features)[:, MIRROR_ORDER]


def _candidates(role: str) -> list[str]:
    """Normalised names that may denote `role`, best first (side before or after the part)."""
    if "_" not in role:
        return list(_PART_ALIASES[role])
    side, part = role.split("_", 1)
    return [
        form
        for alias in _PART_ALIASES[part]
        for word in _SIDE_WORDS[side]
        for form in (word + alias, alias + word)
    ]


def map_joints(names: Sequence[str], joint_map: Mapping[str, str] | None = None) -> dict[str, int]:
    """Index of the joint playing each role in `ROLES`.

    `joint_map` (role → joint name) overrides the automatic choice: the UI-PRMD map when every one
    of its names is present, otherwise the common-name fallback. Raises `SkeletonMismatchError`
    naming the body parts that could not be found.
    """
    if joint_map is None and set(UI_PRMD_JOINTS.values()) <= set(names):
        joint_map = UI_PRMD_JOINTS
    if joint_map is not None:
        index = {name: i for i, name in enumerate(names)}
        found = {role: index[joint_map[role]] for role in ROLES if joint_map.get(role) in index}
    else:
        normalised: dict[str, int] = {}
        for i, name in enumerate(names):
            normalised.setdefault(normalise_name(name), i)
        found = {}
        for role in ROLES:
            hit = next((normalised[c] for c in _candidates(role) if c in normalised), None)
            if hit is not None:
                found[role] = hit
    missing = [role for role in ROLES if role not in found]
    if missing:
        readable = ", ".join(
            role.replace("l_", "left ").replace("r_", "right ") for role in missing
        )
        raise SkeletonMismatchError(f"The skeleton has no joint for: {readable}.")
    return found


def _role_positions(positions: np.ndarray, joints: Mapping[str, int]) -> dict[str, np.ndarray]:
    """(F, 3) trajectory of every role plus the feet midpoint."""
    tracks = {role: positions[:, index, :] for role, index in joints.items()}
    tracks["mid_feet"] = 0.5 * (tracks["l_foot"] + tracks["r_foot"])
    return tracks


def _forward(tracks: Mapping[str, np.ndarray]) -> np.ndarray:
    """(F, 3) unit normal of the frontal plane: (left hip − right hip) × (neck − root).

    Points where the performer faces in a right-handed, y-up rig (BVH, Kinect); a mirrored rig
    flips it.
    """
    normal = np.cross(tracks["l_hip"] - tracks["r_hip"], tracks["neck"] - tracks["root"])
    length = np.linalg.norm(normal, axis=-1, keepdims=True)
    return normal / np.where(length > 0.0, length, 1.0)


def body_size(positions: np.ndarray, joints: Mapping[str, int]) -> float:
    """Approximate standing height (same unit as `positions`) from segment lengths.

    Head–neck–root plus the mean leg (hip–knee–foot); segment lengths do not change with the pose,
    and the median over frames ignores the jitter of markerless capture.
    """
    t = _role_positions(positions, joints)

    def seg(a: str, b: str) -> np.ndarray:
        return np.linalg.norm(t[a] - t[b], axis=-1)

    legs = 0.5 * (
        seg("l_hip", "l_knee")
        + seg("l_knee", "l_foot")
        + seg("r_hip", "r_knee")
        + seg("r_knee", "r_foot")
    )
    size = float(np.median(seg("head", "neck") + seg("neck", "root") + legs))
    if not np.isfinite(size) or size <= 0.0:
        raise SkeletonMismatchError("The skeleton has no size: its joints all lie at one point.")
    return size


def frame_features(
    positions: np.ndarray, names: Sequence[str], joint_map: Mapping[str, str] | None = None
) -> np.ndarray:
    """The 17 body-part distances of every frame, divided by the body size.

    positions: (F, J, 3) world positions (any length unit); names: the J joint names.
    Returns (F, 17) float64, dimensionless (fractions of the standing height), columns as
    `FEATURES`.
    """
    positions = np.asarray(positions, dtype=np.float64)
    if positions.ndim != 3 or positions.shape[1:] != (len(names), 3):
        raise ValueError(f"positions must be (F, {len(names)}, 3), got {positions.shape}")
    if positions.shape[0] == 0:
        raise RecordingTooShortError("The recording has no frames.")
    joints = map_joints(names, joint_map)
    tracks = _role_positions(positions, joints)
    forward = _forward(tracks)
    dist = [
        np.einsum("fk,fk->f", tracks[a] - tracks["root"], forward)
        if b == "front"
        else np.linalg.norm(tracks[a] - tracks[b], axis=-1)
        for _, a, b in FEATURES
    ]
    return np.stack(dist, axis=1) / body_size(positions, joints)


def resample_frames(x: np.ndarray, fps: float, target_fps: float | None) -> np.ndarray:
    """Linear resampling of a (F, D) series from `fps` to `target_fps` (None: unchanged).

    Both retrieval methods see the same frame rate, so recordings captured at different rates
    compare frame for frame, and fewer frames make the quadratic DTW cheaper.
    """
    x = np.asarray(x, dtype=np.float64)
    if target_fps is None or np.isclose(fps, target_fps) or len(x) < 2:
        return x
    duration = (len(x) - 1) / fps
    t_new = np.arange(int(np.floor(duration * target_fps + 1e-9)) + 1) / target_fps
    t_old = np.arange(len(x)) / fps
    return np.stack([np.interp(t_new, t_old, column) for column in x.T], axis=1)


def recording_features(
    positions: np.ndarray,
    names: Sequence[str],
    fps: float,
    *,
    target_fps: float | None = 15.0,
    joint_map: Mapping[str, str] | None = None,
) -> np.ndarray:
    """`frame_features` resampled to `target_fps`: (F', 17) float64, `MotionRetriever`'s input."""
    return resample_frames(frame_features(positions, names, joint_map), fps, target_fps)
