"""The words pages use for what the analysis names internally: one vocabulary for people.

- Body parts: a rig's joint names ("LeftCollar", "UpperArm_L", "joint_Root") become anatomical
  names ("left collarbone", "left upper arm", "body position"). `rig_table` maps every joint of a
  skeleton, using the body parts `analysis.bvh.rigs.identify` finds from the rig's structure;
  `body_part` maps one name alone (pages that have a name but no skeleton), through the same
  keyword table (`analysis.bvh.rigs.parse_name`).
- The playback skeletons: "your movement", "the reference", "the reference adjusted to your level".
- γ is the "level" (`LEVEL_HELP` says what it is in one line).
- Counts agree with their number ("1 repetition").
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from functools import lru_cache

from analysis.bvh import Skeleton
from analysis.bvh.rigs import KEYWORDS, PLAIN, identify, parse_name, plain_name

SKELETON_LABELS = {
    "patient": "your movement",
    "patient_adjusted": "your movement adjusted to the reference",
    "tutor": "the reference",
    "tutor_adjusted": "the reference adjusted to your level",
}
LEVEL_HELP = (
    "Level: how closely a body part follows the reference over the recent sessions, "
    "from 0 (not at all) to 1 (like the reference)."
)
# Trunk and root words the limb keyword table (rigs.KEYWORDS) does not hold.
TRUNK = {
    "root": "body position", "reference": "body position", "hips": "hips", "hip": "hips",
    "pelvis": "hips", "waist": "waist", "spine": "lower back", "spine1": "middle back",
    "spine2": "upper back", "spine3": "upper back", "chest": "chest",
    "upperchest": "upper chest", "neck": "neck", "head": "head", "headtip": "top of the head",
    "headtop": "top of the head", "headend": "top of the head", "torso": "trunk",
    "abdomen": "lower back", "thorax": "chest",
}  # fmt: skip
# Words rigs add that say nothing about the body part.
NOISE = re.compile(r"^(joint|jnt|bone|bip\d*|mixamorig|def|sk|skel)$")
_UNSIDED_LIMB = {"shoulder": "upper arm"}
_WORD = re.compile(r"[A-Z]+(?=[A-Z][a-z])|[A-Z]?[a-z]+|[A-Z]+|[0-9]+")


def _words(name: str) -> list[str]:
    base = re.split(r"[:|]", name)[-1]
    return [w.lower() for w in _WORD.findall(base) if not NOISE.match(w.lower())]


@lru_cache(maxsize=4096)
def body_part(joint: str) -> str:
    """The anatomical name of one rig joint name: "LeftUpperArm" → "left upper arm",
    "RightUpLeg" → "right thigh", "Spine1" → "lower back", "joint_Root" → "body position"."""
    words = _words(str(joint))
    cleaned = "".join(w.capitalize() for w in words) or str(joint)
    side, key = parse_name(cleaned)
    role = KEYWORDS.get(key)
    if role in PLAIN:
        part = PLAIN[role]
    elif role is not None:
        part = _UNSIDED_LIMB.get(role, role.replace("_", " "))
    else:
        raw = "".join(w for w in words if w not in ("left", "right"))  # keeps "spine1"
        trunk = TRUNK.get(raw) or TRUNK.get(key) or TRUNK.get(key.rstrip("0123456789"))
        part = trunk or " ".join(words) or str(joint).lower()
    return f"{side} {part}" if side else part


def rig_table(skeleton: Skeleton) -> dict[str, str]:
    """Every joint of a skeleton → its anatomical name; the parts found from the rig's structure
    (`identify`) win over the name alone, so "LeftShoulder" is the collarbone in a rig with an
    upper-arm joint below it and the upper arm in one without."""
    table = {name: body_part(name) for name in skeleton.names}
    n_joints = len(skeleton.names)
    for role, point in identify(skeleton).items():
        if point < n_joints:
            table[skeleton.names[point]] = plain_name(role)
    return table


def plural(count: int | float | None, word: str, many: str | None = None) -> str:
    """ "1 repetition", "3 repetitions", "0 repetitions"."""
    n = 0 if count is None else count
    return f"{n} {word if n == 1 else (many or word + 's')}"


ORDINALS = ("first", "second", "third", "fourth", "fifth", "sixth", "seventh", "eighth", "ninth")
_NUMBERED = re.compile(r"\s*(key\s*)?pose\s*\d+\s*", re.IGNORECASE)


def key_pose_name(kind: int | str, names: Mapping[str, str] | None = None) -> str:
    """The exercise's name for a kind of key pose ("start", "end of range"); kinds nobody named
    (or named only by number, "key pose 2") are described by their place in the movement."""
    name = str((names or {}).get(str(kind)) or "").strip()
    if name and not _NUMBERED.fullmatch(name):
        return name
    try:
        index = int(kind) - 1
    except (TypeError, ValueError):
        return "a marked position of the movement"
    place = ORDINALS[index] if 0 <= index < len(ORDINALS) else "another"
    return f"{place} marked position of the movement"


_FILE_WORDS = (
    (re.compile(r"but the skeleton has (\d+) channels"), r"but the skeleton needs \1 per frame"),
    (re.compile(r"(\d+) frames × (\d+) channels"), r"\1 frames of \2 values"),
    (re.compile(r"\bposition channels\b"), "position values"),
    (re.compile(r"\bchannels\b"), "motion values"),
    (re.compile(r"\bchannel\b"), "motion value"),
)


def file_problem(message: str) -> str:
    """A BVH reader's message in the words of the upload page: what a frame holds is "values",
    not the format's "channels" (the keyword CHANNELS, as written in the file, stays)."""
    for pattern, words in _FILE_WORDS:
        message = pattern.sub(words, message)
    return message
