"""Mapping the joints of another BVH rig onto an exercise model's joint names.

A recording made with another exporter names the same joints differently (``LeftUpLeg`` for
``LeftUpperLeg``, ``KneeLeft`` for ``LeftLowerLeg``). Each row of `SYNONYMS` lists the names one
body joint goes by in common rigs (Kinect SDK, UI-PRMD, CMU, Mixamo, Bandai-Namco); names are
compared case- and punctuation-insensitively, after dropping a ``namespace:`` prefix. A recording
maps onto a model when every joint the model needs is found either by its own name or through a
row of the table; otherwise `SkeletonMismatchError` names the joints that are missing.

This matches names only, for callers that have no skeleton. Recordings of other rigs are put on an
exercise's skeleton by `analysis.kinematics.map_onto` (`analysis.bvh.rigs` finds the body parts by
names, chain and rest pose; `analysis.kinematics.retarget` transfers the segment rotations).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping

from analysis.bvh.errors import SkeletonMismatchError

SYNONYMS: tuple[tuple[str, ...], ...] = (
    ("Waist", "Hips", "Hip", "Pelvis", "SpineBase", "Root"),
    ("Spine", "SpineMid", "Spine1", "Abdomen"),
    ("Chest", "SpineShoulder", "Spine2", "Chest2", "UpperChest"),
    ("Neck", "Neck1"),
    ("Head",),
    ("HeadTip", "HeadEnd", "HeadTop_End"),
    ("LeftCollar", "LeftShoulder", "ShoulderLeft_Collar", "Shoulder_L", "LCollar", "LeftClavicle"),
    ("LeftUpperArm", "ShoulderLeft", "LeftArm", "UpperArm_L", "LShoulder", "LUpArm"),
    ("LeftForearm", "ElbowLeft", "LeftForeArm", "LowerArm_L", "LElbow", "LeftLowerArm"),
    ("LeftHand", "WristLeft", "Hand_L", "LWrist", "LHand"),
    ("RightCollar", "RightShoulder", "Shoulder_R", "RCollar", "RightClavicle"),
    ("RightUpperArm", "ShoulderRight", "RightArm", "UpperArm_R", "RShoulder", "RUpArm"),
    ("RightForearm", "ElbowRight", "RightForeArm", "LowerArm_R", "RElbow", "RightLowerArm"),
    ("RightHand", "WristRight", "Hand_R", "RWrist", "RHand"),
    ("LeftUpperLeg", "HipLeft", "LeftUpLeg", "UpperLeg_L", "LeftThigh", "LHip", "LThigh"),
    ("LeftLowerLeg", "KneeLeft", "LeftLeg", "LowerLeg_L", "LeftShin", "LKnee", "LShin"),
    ("LeftFoot", "AnkleLeft", "Foot_L", "LAnkle", "LFoot"),
    ("LeftToes", "FootLeft", "LeftToeBase", "Toes_L", "LToe", "LeftToe"),
    ("RightUpperLeg", "HipRight", "RightUpLeg", "UpperLeg_R", "RightThigh", "RHip", "RThigh"),
    ("RightLowerLeg", "KneeRight", "RightLeg", "LowerLeg_R", "RightShin", "RKnee", "RShin"),
    ("RightFoot", "AnkleRight", "Foot_R", "RAnkle", "RFoot"),
    ("RightToes", "FootRight", "RightToeBase", "Toes_R", "RToe", "RightToe"),
)


def normalise_name(name: str) -> str:
    """Lower-case letters and digits of a joint name, without a ``namespace:`` prefix."""
    return re.sub(r"[^0-9a-z]", "", name.rsplit(":", 1)[-1].lower())


def _synonym_rows() -> dict[str, int]:
    rows: dict[str, int] = {}
    for row, names in enumerate(SYNONYMS):
        for name in names:
            rows.setdefault(normalise_name(name), row)
    return rows


_ROW_OF = _synonym_rows()


def map_joints(wanted: Iterable[str], available: Iterable[str]) -> dict[str, str]:
    """For every wanted (model) joint, the name of the matching joint among ``available``.

    Exact names win; then the same normalised name; then a synonym from the same table row.
    Raises SkeletonMismatchError listing the wanted joints that have no match.
    """
    available = list(available)
    by_norm = {normalise_name(n): n for n in available}
    by_row = {_ROW_OF[k]: n for k, n in by_norm.items() if k in _ROW_OF}
    mapping: dict[str, str] = {}
    missing = []
    for name in wanted:
        key = normalise_name(name)
        found = name if name in available else by_norm.get(key)
        if found is None and key in _ROW_OF:
            found = by_row.get(_ROW_OF[key])
        if found is None:
            missing.append(name)
        else:
            mapping[name] = found
    if missing:
        shown = ", ".join(missing[:6]) + (" …" if len(missing) > 6 else "")
        raise SkeletonMismatchError(
            f"The recording's skeleton does not match the exercise: no joint for {shown}."
        )
    return mapping


def reorder_indices(mapping: Mapping[str, str], names: tuple[str, ...]) -> list[int]:
    """Indices into ``names`` of the mapped joints, in the order of ``mapping``."""
    return [names.index(mapping[k]) for k in mapping]
