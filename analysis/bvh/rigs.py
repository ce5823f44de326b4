"""Which joint of a skeleton is which body part, whatever the rig that wrote it.

A *role* is a body part the analysis can use: the hips (where the legs branch), the chest (where the
arms branch), neck, head, top of the head, and on each side the collarbone, upper arm, forearm,
hand, thigh, lower leg, foot and toes. `identify` finds them in three steps:

1. **Names.** A joint name is split into words (``LeftUpLeg`` → left, up, leg; ``UpArm_L``;
   ``mixamorig:LeftForeArm``; ``Bip01 L Thigh``; ``LUArm``), its side is read from a word or a
   one-letter prefix/suffix, and the rest is looked up in `KEYWORDS`. The table covers the rigs
   clinics use: Kinect v1/v2/Azure (``KneeLeft``, ``AnkleLeft``/``FootLeft``), UI-PRMD, CMU
   conversions (``LeftUpLeg``, ``LeftHip``/``LeftKnee``/``LeftAnkle``, ``LeftCollar``), Mixamo,
   Xsens MVN, Perception Neuron, Rokoko, OptiTrack Motive (``LThigh``, ``LUArm``, ``LFArm``),
   Vicon, MakeHuman/Blender (``clavicle.L``, ``upper_arm.L``, ``LoLeg_L``), 3ds Max Biped, and
   video-based pose estimators (``LeftShoulder`` → ``LeftElbow`` → ``LeftWrist``).
2. **Structure.** Words that mean different parts in different rigs are settled by the chain:
   ``Shoulder`` is the collarbone when an upper-arm joint follows it on the same side (Mixamo,
   Xsens) and the upper arm otherwise (CMU's ``LeftCollar``/``LeftShoulder``, Kinect, video
   estimators); of ``Ankle`` and ``Foot`` on one chain the first is the ankle and the second the
   toes (Kinect v2). The hips are the lowest common ancestor of the two thighs and the chest that
   of the two collarbones (or upper arms), so spines with one to five joints, a static root above
   the hips or a spine that starts above the root (MakeHuman) all work. Every limb must run
   thigh → lower leg → foot → toes (arm: collarbone → upper arm → forearm → hand) down the tree.
3. **Geometry.** A part named without a side (``Thigh``, ``Thigh.001``) gets its side from the rest
   pose: left is up × forward, with up from hips to chest and forward from ankle to toes.

Where a rig has no joint for the top of the head or the toes, the End Site of the head or foot
stands in. Points are numbered joints first, then End Sites (J + k).
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from analysis.bvh.errors import SkeletonMismatchError
from analysis.bvh.io import Skeleton

FloatArray = npt.NDArray[np.float64]
SIDES = ("left", "right")
LIMB_ROLES = (
    "collar", "upper_arm", "forearm", "hand", "upper_leg", "lower_leg", "foot", "toes",
)  # fmt: skip
CENTRE_ROLES = ("pelvis", "chest", "neck", "head", "head_top")
ARM = ("collar", "upper_arm", "forearm", "hand")
LEG = ("upper_leg", "lower_leg", "foot", "toes")
# Parts without which a recording cannot be compared with an exercise that has them.
REQUIRED = frozenset(
    {"pelvis", "chest", "head"}
    | {f"{s}_{r}" for s in SIDES for r in ("upper_arm", "forearm", "hand")}
    | {f"{s}_{r}" for s in SIDES for r in ("upper_leg", "lower_leg", "foot")}
)
PLAIN = {
    "pelvis": "hips", "chest": "chest", "neck": "neck", "head": "head",
    "head_top": "top of the head", "collar": "collarbone", "upper_arm": "upper arm",
    "forearm": "forearm", "hand": "hand", "upper_leg": "thigh", "lower_leg": "lower leg",
    "foot": "foot", "toes": "toes",
}  # fmt: skip

# Name (words joined, side and trailing digits removed) → role; "shoulder", "ankle" and "hip" are
# settled by the chain (see `_settle`).
KEYWORDS = {
    "collar": "collar", "clavicle": "collar", "clav": "collar", "scapula": "collar",
    "shoulderblade": "collar",
    "upperarm": "upper_arm", "arm": "upper_arm", "uparm": "upper_arm", "uarm": "upper_arm",
    "humerus": "upper_arm", "bicep": "upper_arm",
    "forearm": "forearm", "lowerarm": "forearm", "loarm": "forearm", "farm": "forearm",
    "elbow": "forearm", "forarm": "forearm", "radius": "forearm",
    "hand": "hand", "wrist": "hand",
    "upleg": "upper_leg", "upperleg": "upper_leg", "thigh": "upper_leg", "femur": "upper_leg",
    "uleg": "upper_leg", "hip": "upper_leg",
    "leg": "lower_leg", "lowerleg": "lower_leg", "loleg": "lower_leg", "knee": "lower_leg",
    "shin": "lower_leg", "calf": "lower_leg", "tibia": "lower_leg", "lleg": "lower_leg",
    "foot": "foot", "ankle": "foot",
    "toe": "toes", "toes": "toes", "toebase": "toes", "ball": "toes", "football": "toes",
    "shoulder": "shoulder",
    "neck": "neck",
    "head": "head",
    "headtop": "head_top", "headend": "head_top", "headtip": "head_top", "headtopend": "head_top",
    "headnub": "head_top", "headsite": "head_top", "top": "head_top",
}  # fmt: skip
_NOISE = frozenset({"bip", "mixamorig", "def", "orig", "jnt", "bone", "biped", "sk", "skel", "mch"})
_LEFT = frozenset({"left", "l", "lft", "lt"})
_RIGHT = frozenset({"right", "r", "rgt", "rt"})


def name_words(name: str) -> list[str]:
    """Lower-case words of a joint name: namespaces dropped, camelCase and separators split."""
    base = name.rsplit(":", 1)[-1]
    base = re.sub(r"([a-z0-9])([A-Z])", r"\1 \2", base)
    base = re.sub(r"([A-Z]+)([A-Z][a-z])", r"\1 \2", base)
    words = [w.lower() for w in re.split(r"[^0-9A-Za-z]+", base) if w]
    return [w for w in words if w.rstrip("0123456789") not in _NOISE]


def _strip_digits(key: str) -> str:
    return key.rstrip("0123456789")


def parse_name(name: str) -> tuple[str | None, str]:
    """(side or None, key) of a joint name: ``'LeftUpLeg'`` → ``('left', 'upleg')``."""
    words = name_words(name)
    side = None
    rest = []
    for word in words:
        if word in _LEFT and side is None:
            side = "left"
        elif word in _RIGHT and side is None:
            side = "right"
        else:
            rest.append(word)
    key = _strip_digits("".join(rest))
    if side is None:
        for prefix, which in (("left", "left"), ("right", "right"), ("l", "left"), ("r", "right")):
            if key.startswith(prefix) and _strip_digits(key[len(prefix) :]) in KEYWORDS:
                return which, _strip_digits(key[len(prefix) :])
        for suffix, which in (("left", "left"), ("right", "right")):
            if key.endswith(suffix) and key[: -len(suffix)] in KEYWORDS:
                return which, key[: -len(suffix)]
    return side, key


def rest_points(skeleton: Skeleton) -> FloatArray:
    """World positions of joints then End Sites in the rest pose (every channel zero): (J+E, 3).

    Position channels replace the OFFSET in `Motion.frames`, so at rest a joint sits at its OFFSET.
    """
    n = len(skeleton.names)
    out = np.zeros((n + len(skeleton.end_site_parents), 3))
    for j in range(n):
        p = int(skeleton.parents[j])
        out[j] = skeleton.offsets[j] + (out[p] if p >= 0 else 0.0)
    for k, p in enumerate(skeleton.end_site_parents):
        out[n + k] = out[int(p)] + skeleton.end_site_offsets[k]
    return out


def _ancestors(parents: Sequence[int], joint: int) -> list[int]:
    """joint, its parent, …, the root."""
    chain = []
    while joint >= 0:
        chain.append(joint)
        joint = int(parents[joint])
    return chain


def common_ancestor(parents: Sequence[int], a: int, b: int) -> int:
    above_a = set(_ancestors(parents, a))
    return next(j for j in _ancestors(parents, b) if j in above_a)


def is_ancestor(parents: Sequence[int], a: int, b: int) -> bool:
    """Whether joint a is b or above b."""
    return a in _ancestors(parents, b)


def _depths(parents: Sequence[int]) -> list[int]:
    return [len(_ancestors(parents, j)) - 1 for j in range(len(parents))]


def _candidates(skeleton: Skeleton) -> dict[tuple[str | None, str], list[int]]:
    """(side, keyword role) → joints, in file order."""
    found: dict[tuple[str | None, str], list[int]] = {}
    for j, name in enumerate(skeleton.names):
        side, key = parse_name(name)
        role = KEYWORDS.get(key)
        if side is None and key == "hip":
            continue  # OptiTrack's "Hip" is the pelvis, found from the thighs
        if role is not None:
            found.setdefault((side, role), []).append(j)
    return found


def _pick(joints: list[int], skeleton: Skeleton, depth: list[int]) -> int | None:
    """The shallowest joint, preferring names without a helper's leading underscore."""
    if not joints:
        return None
    return min(joints, key=lambda j: (skeleton.names[j].startswith("_"), depth[j], j))


def _assign_unsided(found: dict[tuple[str | None, str], list[int]], skeleton: Skeleton) -> None:
    """Give a side to limb parts named without one, from the rest pose (see the docstring)."""
    unsided = [r for (s, r) in found if s is None and r in (*LIMB_ROLES, "shoulder")]
    if not unsided:
        return
    rest = rest_points(skeleton)
    feet = found.get((None, "foot"), []) + found.get(("left", "foot"), [])
    feet += found.get(("right", "foot"), [])
    forward = np.zeros(3)
    for f in feet:
        for c in skeleton.children(f):
            forward += rest[c] - rest[f]
    head = found.get((None, "head"), [])
    up = (rest[head[0]] - rest[0]) if head else np.array([0.0, 1.0, 0.0])
    lateral = np.cross(up, forward)
    if np.linalg.norm(lateral) < 1e-9:
        return
    for role in unsided:
        joints = found.pop((None, role))
        for j in joints:
            side = "left" if float(np.dot(rest[j] - rest[0], lateral)) > 0 else "right"
            found.setdefault((side, role), []).append(j)


def _settle(
    found: dict[tuple[str | None, str], list[int]], skeleton: Skeleton, side: str
) -> dict[str, int]:
    """Roles of one side's limbs, with the chain settling 'shoulder' and 'ankle'/'foot'."""
    parents = [int(p) for p in skeleton.parents]
    depth = _depths(parents)
    get = {role: list(found.get((side, role), [])) for role in (*LIMB_ROLES, "shoulder")}
    for shoulder in get.pop("shoulder"):
        below = any(is_ancestor(parents, shoulder, a) for a in get["upper_arm"] if a != shoulder)
        get["collar" if below else "upper_arm"].append(shoulder)
    ankles = [j for j in get["foot"] if parse_name(skeleton.names[j])[1] == "ankle"]
    feet = [j for j in get["foot"] if j not in ankles]
    if ankles and feet:
        ankle = _pick(ankles, skeleton, depth)
        later = [f for f in feet if ankle is not None and is_ancestor(parents, ankle, f)]
        get["foot"] = ankles
        if not get["toes"]:
            get["toes"] = later
    roles: dict[str, int] = {}
    for role in LIMB_ROLES:
        joint = _pick(get[role], skeleton, depth)
        if joint is not None:
            roles[role] = joint
    for chain in (ARM, LEG):
        kept = None  # a limb part below one that was dropped is checked against the one above it
        for role in [r for r in chain if r in roles]:
            if kept is not None and not is_ancestor(parents, roles[kept], roles[role]):
                del roles[role]
            else:
                kept = role
    return roles


def _end_site_of(skeleton: Skeleton, joint: int) -> int | None:
    """The point index of the joint's farthest End Site, if it has one of non-zero length."""
    n = len(skeleton.names)
    best, length = None, 1e-9
    for k, p in enumerate(skeleton.end_site_parents):
        size = float(np.linalg.norm(skeleton.end_site_offsets[k]))
        if int(p) == joint and size > length:
            best, length = n + k, size
    return best


def identify(skeleton: Skeleton) -> dict[str, int]:
    """Body part → point index (joint, or J + k for End Site k); see the module docstring.

    Keys: ``pelvis``, ``chest``, ``neck``, ``head``, ``head_top`` and ``left_…``/``right_…`` for
    ``collar``, ``upper_arm``, ``forearm``, ``hand``, ``upper_leg``, ``lower_leg``, ``foot``,
    ``toes``. Parts that cannot be found are absent.
    """
    found = _candidates(skeleton)
    _assign_unsided(found, skeleton)
    parents = [int(p) for p in skeleton.parents]
    roles: dict[str, int] = {}
    for side in SIDES:
        for role, joint in _settle(found, skeleton, side).items():
            roles[f"{side}_{role}"] = joint
    if "left_upper_leg" in roles and "right_upper_leg" in roles:
        roles["pelvis"] = common_ancestor(
            parents, roles["left_upper_leg"], roles["right_upper_leg"]
        )
    for part in ("collar", "upper_arm"):
        if f"left_{part}" in roles and f"right_{part}" in roles:
            roles["chest"] = common_ancestor(parents, roles[f"left_{part}"], roles[f"right_{part}"])
            break
    _head_roles(skeleton, found, roles)
    for side in SIDES:
        foot = roles.get(f"{side}_foot")
        tip = _end_site_of(skeleton, foot) if foot is not None else None
        if tip is not None and f"{side}_toes" not in roles:
            roles[f"{side}_toes"] = tip
    return roles


def _head_roles(
    skeleton: Skeleton, found: dict[tuple[str | None, str], list[int]], roles: dict[str, int]
) -> None:
    """Head, neck and top of the head, all above the chest."""
    parents = [int(p) for p in skeleton.parents]
    depth = _depths(parents)
    chest = roles.get("chest", 0)
    heads = [j for j in found.get((None, "head"), []) if is_ancestor(parents, chest, j)]
    head = _pick(heads, skeleton, depth)
    if head is None and "chest" in roles:
        head = _head_by_structure(skeleton, roles)
    if head is None:
        return
    roles["head"] = head
    necks = [
        j
        for j in found.get((None, "neck"), [])
        if is_ancestor(parents, chest, j)
        and is_ancestor(parents, j, head)
        and j not in (head, chest)
    ]
    if (neck := _pick(necks, skeleton, depth)) is not None:
        roles["neck"] = neck
    tops = [j for j in found.get((None, "head_top"), []) if is_ancestor(parents, head, j)]
    top = _pick(tops, skeleton, depth)
    if top is None:
        top = _end_site_of(skeleton, head)
    if top is not None:
        roles["head_top"] = top


def _head_by_structure(skeleton: Skeleton, roles: dict[str, int]) -> int | None:
    """No joint named head (Blender's ``spine.006``): the end of the chain that leaves the chest
    away from both arms, if it is at least one joint long."""
    parents = [int(p) for p in skeleton.parents]
    arms = [roles[f"{s}_{r}"] for s in SIDES for r in ARM if f"{s}_{r}" in roles]
    joint = roles["chest"]
    kids = [
        c for c in skeleton.children(joint) if not any(is_ancestor(parents, c, a) for a in arms)
    ]
    if not kids:
        return None
    joint = kids[0]
    while nxt := skeleton.children(joint):
        joint = nxt[0]
    return joint


def plain_name(role: str) -> str:
    """'left_forearm' → 'left forearm'."""
    side, _, part = role.partition("_")
    if side in SIDES:
        return f"{side} {PLAIN[part]}"
    return PLAIN[role]


def _join_plain(roles: Sequence[str]) -> str:
    words = [plain_name(r) for r in roles]
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


ORDER = (
    "pelvis", "chest", "neck", "head", "head_top",
    *(f"{s}_{r}" for s in SIDES for r in (*ARM, *LEG)),
)  # fmt: skip


def correspond(source: Skeleton, target: Skeleton) -> dict[str, tuple[int, int]]:
    """For every body part both skeletons have: (target joint, source point).

    Raises SkeletonMismatchError, naming in plain words the parts the exercise needs that the
    recording lacks, when a required part of the target is not found in the source.
    """
    src, tgt = identify(source), identify(target)
    n_target = len(target.names)
    wanted = [r for r in ORDER if r in tgt and tgt[r] < n_target]
    missing = [r for r in wanted if r in REQUIRED and r not in src]
    if "pelvis" not in tgt or "chest" not in tgt:
        raise SkeletonMismatchError(
            "The exercise's reference skeleton has no recognisable hips and chest, so recordings "
            "from other capture systems cannot be matched to it; upload a recording made with the "
            "same capture system as the exercise's reference."
        )
    if missing:
        shown = missing if len(missing) <= 8 else missing[:7]
        more = "" if len(missing) <= 8 else f" (and {len(missing) - 7} more parts)"
        raise SkeletonMismatchError(
            "The recording's skeleton does not match the exercise's: it has no joint we "
            f"recognise as the {_join_plain(shown)}{more}. Export the recording with a full-body "
            "skeleton, or record a reference for this exercise with this capture system."
        )
    return {r: (tgt[r], src[r]) for r in wanted if r in src}
