"""Clinical angles in plain words, grouped by body region, for pages and reports.

``angle_label("knee_flexion_left")`` is "Left knee flexion"; `angle_groups` puts the angles of a
result into regions (trunk, hips, knees, ankles, shoulders, elbows) beside their normal adult
range, flagging values outside it, with the angles the recording could not measure and why, the
regions the exercise moves first; `symmetry_rows` sets each left range beside the right one.
`involves_arms` decides from an exercise's involved joint names whether it is an exercise of the
upper limb (the reachable workspace is measured then).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any, Protocol

from analysis.bvh.skeleton_map import normalise_name
from analysis.clinical.body import _ROLE_BY_NAME
from analysis.clinical.norms import norm_for

# region title -> angle names without side, in the order a therapist reads them
REGIONS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("Trunk", ("trunk_flexion", "trunk_lateral_flexion")),
    ("Hips", ("hip_flexion", "hip_abduction")),
    ("Knees", ("knee_flexion",)),
    ("Ankles", ("ankle_dorsiflexion",)),
    (
        "Shoulders",
        (
            "shoulder_elevation",
            "shoulder_flexion",
            "shoulder_abduction",
            "shoulder_plane_of_elevation",
            "shoulder_rotation",
        ),
    ),
    ("Elbows", ("elbow_flexion",)),
)
MOTIONS = {
    "trunk_flexion": "Trunk flexion",
    "trunk_lateral_flexion": "Trunk side bending (to the right +)",
    "hip_flexion": "hip flexion",
    "hip_abduction": "hip abduction",
    "knee_flexion": "knee flexion",
    "ankle_dorsiflexion": "ankle dorsiflexion",
    "shoulder_flexion": "shoulder flexion",
    "shoulder_abduction": "shoulder abduction",
    "shoulder_elevation": "shoulder elevation (arm to trunk)",
    "shoulder_plane_of_elevation": "shoulder: direction the arm is raised in (0° to the side, "
    "90° forward)",
    "shoulder_rotation": "shoulder rotation (inward +, outward −)",
    "elbow_flexion": "elbow flexion",
}
# body role of a joint (analysis.clinical.body) -> the region whose angles it moves
_REGION_OF_ROLE = {
    "pelvis": "Trunk", "spine": "Trunk", "chest": "Trunk", "neck": "Trunk",
    "hip": "Hips", "knee": "Knees", "ankle": "Ankles", "toe": "Ankles",
    "collar": "Shoulders", "shoulder": "Shoulders", "elbow": "Elbows", "wrist": "Elbows",
}  # fmt: skip
ARM_WORDS = ("shoulder", "elbow", "wrist", "hand", "arm")
LEG_WORDS = ("leg", "thigh", "knee", "shin", "ankle", "foot", "toe")
SIDE_WORDS = {"left": "Left", "right": "Right"}
QUADRANT_LABELS = {
    "upper_medial": "upper, towards the body",
    "upper_lateral": "upper, away from the body",
    "lower_medial": "lower, towards the body",
    "lower_lateral": "lower, away from the body",
}


class RangeLike(Protocol):
    @property
    def min(self) -> float: ...

    @property
    def max(self) -> float: ...

    @property
    def range(self) -> float: ...


def split_side(name: str) -> tuple[str, str]:
    """("knee_flexion", "left") for "knee_flexion_left"; ("trunk_flexion", "") without a side."""
    for side in SIDE_WORDS:
        if name.endswith(f"_{side}"):
            return name[: -len(side) - 1], side
    return name, ""


def angle_label(name: str) -> str:
    """The plain-words name of a clinical angle: "Left knee flexion", "Trunk flexion"."""
    base, side = split_side(name)
    motion = MOTIONS.get(base, base.replace("_", " "))
    return f"{SIDE_WORDS[side]} {motion}" if side else motion[:1].upper() + motion[1:]


def region_of(name: str) -> str:
    base, _ = split_side(name)
    return next((title for title, names in REGIONS if base in names), "Other")


def _role_base(joint: str) -> str:
    role = _ROLE_BY_NAME.get(normalise_name(joint), "")
    return split_side(role)[0]


def involved_regions(joints: Iterable[str]) -> set[str]:
    """Regions whose angles the named skeleton joints move (any rig's names)."""
    return {_REGION_OF_ROLE[r] for r in map(_role_base, joints) if r in _REGION_OF_ROLE}


def _is_arm(joint: str) -> bool:
    name = normalise_name(joint)
    return any(w in name for w in ARM_WORDS) or _role_base(joint) in ("shoulder", "elbow", "wrist")


def _is_leg(joint: str) -> bool:
    name = normalise_name(joint)
    return any(w in name for w in LEG_WORDS) or _role_base(joint) in ("hip", "knee", "ankle", "toe")


def involves_arms(joints: Iterable[str]) -> bool:
    """Whether an exercise is one of the upper limb: its involved joints include arm joints
    (shoulder, elbow, wrist, hand, by the rig's name or the body role the name maps to), more
    of them than leg joints. A squat whose tutor swings the arms for balance is not one."""
    joints = list(joints)
    arms = sum(map(_is_arm, joints))
    return arms > 0 and arms > sum(map(_is_leg, joints))


def beyond_normal(name: str, angle: RangeLike) -> str:
    """Plain words for a recorded range outside the normal adult one ("" inside it)."""
    norm = norm_for(name)
    words = [
        f"{angle.max - norm.maximum:.0f}° above" if angle.max > norm.maximum + 0.5 else "",
        f"{norm.minimum - angle.min:.0f}° below" if angle.min < norm.minimum - 0.5 else "",
    ]
    said = " and ".join(w for w in words if w)
    return f"{said} the normal range" if said else ""


def angle_row(name: str, angle: RangeLike) -> dict[str, Any]:
    norm = norm_for(name)
    return {
        "name": name,
        "label": angle_label(name),
        "min": angle.min,
        "max": angle.max,
        "range": angle.range,
        "norm_min": norm.minimum,
        "norm_max": norm.maximum,
        "norm_range": norm.range,
        "percent_of_norm": round(100.0 * angle.range / norm.range) if norm.range else None,
        "flag": beyond_normal(name, angle),
    }


def note_row(name: str, note: str) -> dict[str, Any]:
    """An angle the recording does not measure: its label and the reason, no figures."""
    return {"name": name, "label": angle_label(name), "note": note}


def angle_groups(
    angles: Mapping[str, RangeLike],
    involved_joints: Iterable[str] = (),
    notes: Mapping[str, str] | None = None,
) -> list[dict[str, Any]]:
    """The angles of a result by region: ``[{"region", "involved", "rows": [angle_row…],
    "notes": [note_row…]}]``, regions the exercise moves first, then the others, each in
    `REGIONS` order; ``notes``: the result's ``clinical_notes`` (angles not measured, why)."""
    moved, notes = involved_regions(involved_joints), notes or {}
    groups = []
    for title, bases in REGIONS:
        names = [n for base in bases for n in (base, f"{base}_left", f"{base}_right")]
        rows = [angle_row(name, angles[name]) for name in names if name in angles]
        unmeasured = [note_row(n, notes[n]) for n in names if n in notes and n not in angles]
        if rows or unmeasured:
            groups.append(
                {"region": title, "involved": title in moved, "rows": rows, "notes": unmeasured}
            )
    return sorted(groups, key=lambda g: not g["involved"])


def symmetry_rows(angles: Mapping[str, RangeLike]) -> list[dict[str, Any]]:
    """Each angle measured on both sides: ``{"label", "left", "right", "difference"}``, the
    ranges in degrees and left minus right (the larger side's excess), in `REGIONS` order."""
    rows = []
    for _, bases in REGIONS:
        for base in bases:
            left, right = angles.get(f"{base}_left"), angles.get(f"{base}_right")
            if left is not None and right is not None:
                label = MOTIONS.get(base, base)
                rows.append({
                    "label": label[:1].upper() + label[1:],
                    "left": left.range,
                    "right": right.range,
                    "difference": round(left.range - right.range, 2),
                })  # fmt: skip
    return rows


# Corrections (analysis.feedback.advice): the body part each clinical angle moves, in plain
# words, and how a patient is told to change it: (kind of finding → direction word, instruction).
# "less" = a smaller range than the tutor's, "more" = a larger one, "extra" = moving a part the
# tutor keeps still. The instruction holds {part}; the past tense says what the part did.
ANGLE_PARTS = {
    "knee_flexion": "knee", "hip_flexion": "hip", "hip_abduction": "leg",
    "ankle_dorsiflexion": "ankle", "shoulder_flexion": "arm", "shoulder_abduction": "arm",
    "shoulder_elevation": "arm", "shoulder_rotation": "arm",
    "elbow_flexion": "elbow", "trunk_flexion": "trunk", "trunk_lateral_flexion": "trunk",
}  # fmt: skip
ANGLE_PAST = {
    "knee_flexion": "bent", "hip_flexion": "bent", "hip_abduction": "moved out",
    "ankle_dorsiflexion": "bent", "shoulder_flexion": "rose", "shoulder_abduction": "rose",
    "shoulder_elevation": "rose", "shoulder_rotation": "turned",
    "elbow_flexion": "bent", "trunk_flexion": "leaned", "trunk_lateral_flexion": "bent sideways",
}  # fmt: skip
INSTRUCTIONS: dict[tuple[str, str], tuple[str, str]] = {
    ("knee_flexion", "less"): ("bend", "Bend your {part} more"),
    ("knee_flexion", "more"): ("straighten", "Bend your {part} less (straighten it sooner)"),
    ("hip_flexion", "less"): ("bend", "Bend more at your {part}"),
    ("hip_flexion", "more"): ("straighten", "Bend less at your {part}"),
    ("hip_abduction", "less"): ("raise", "Raise your {part} further out to the side"),
    ("hip_abduction", "more"): ("lower", "Lower your {part}: keep it closer to the other"),
    ("ankle_dorsiflexion", "less"): ("bend", "Bend your {part} more"),
    ("ankle_dorsiflexion", "more"): ("straighten", "Bend your {part} less"),
    ("shoulder_flexion", "less"): ("raise", "Raise your {part} higher in front of you"),
    ("shoulder_flexion", "more"): ("lower", "Lower your {part}: not as high in front of you"),
    ("shoulder_abduction", "less"): ("raise", "Raise your {part} higher out to the side"),
    ("shoulder_abduction", "more"): ("lower", "Lower your {part}: not as high out to the side"),
    ("shoulder_elevation", "less"): ("raise", "Raise your {part} higher"),
    ("shoulder_elevation", "more"): ("lower", "Lower your {part}: not as high"),
    ("shoulder_rotation", "less"): ("turn", "Turn your {part} further, swinging the forearm wider"),
    ("shoulder_rotation", "more"): (
        "turn",
        "Turn your {part} less far: a smaller swing of the forearm",
    ),
    ("elbow_flexion", "less"): ("bend", "Bend your {part} more"),
    ("elbow_flexion", "more"): ("straighten", "Straighten your {part} more"),
    ("trunk_flexion", "less"): ("lean", "Lean your {part} further forward"),
    ("trunk_flexion", "more"): ("straighten", "Straighten your {part}: lean forward less"),
    ("trunk_lateral_flexion", "less"): ("bend", "Bend your {part} further to the side"),
    ("trunk_lateral_flexion", "more"): ("straighten", "Straighten your {part}: lean sideways less"),
}
STILL_INSTRUCTION = ("keep still", "Keep your {part} still")


def angle_part(name: str) -> str:
    """The body part a clinical angle moves, in plain words: "left knee", "trunk"."""
    base, side = split_side(name)
    part = ANGLE_PARTS.get(base, base.split("_")[0])
    return f"{side} {part}" if side else part
