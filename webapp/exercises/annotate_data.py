"""What the key-pose page draws and fills in, computed from the exercise's tutor.

- `angle_curves`: per joint, how far its rotation is from the rest pose in every frame (degrees).
- `movement_order`: joints by how much they move (range of that angle), the most first; the page
  opens on the first, the joint the exercise is about, never on one that barely moves.
- `tutor_pose`: the tutor's world positions for the 3D view (the recording viewer's layout).
- `default_grammar_text`: the feedback grammar a new exercise is given (`analysis.feedback.
  default_grammar`, as `analysis.pipeline.build_model` writes it) with body parts written in
  plain words; the grammar matches them to the rig's joints by their readable form.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Mapping
from typing import Any

import numpy as np

from analysis.bvh import Motion, Skeleton
from analysis.feedback import Grammar, GrammarError, default_grammar
from analysis.feedback.grammar import rename_joints
from analysis.feedback.text import joint_label
from analysis.kinematics import positions, rotations
from analysis.pipeline.model_fit import moving_joints
from webapp.exercises import body_parts
from webapp.recordings.words import key_pose_name

DEFAULT_GRAMMAR_JOINTS = 3  # joints a default grammar speaks of when the key poses pick none
_WRITABLE = re.compile(r"[A-Za-z_][A-Za-z0-9_.:]*")  # a joint name the grammar reads


def angle_curves(motion: Motion) -> dict[str, list[float]]:
    """Per joint, the angle (deg) of its local rotation in every frame, rounded to 0.1°."""
    quats = rotations(motion)  # (F, J, 4) unit quaternions w, x, y, z
    angles = np.degrees(2.0 * np.arccos(np.clip(np.abs(quats[..., 0]), 0.0, 1.0)))
    return {
        name: np.round(angles[:, j], 1).tolist() for j, name in enumerate(motion.skeleton.names)
    }


def movement_order(curves: dict[str, list[float]], names: tuple[str, ...]) -> list[str]:
    """Joint names by the range of their angle, largest first. The root comes last: its angle
    is the whole body's turn in the room, not a movement of a body part."""
    spread = {name: float(np.ptp(curves[name])) if curves[name] else 0.0 for name in names}
    parts = sorted(names[1:], key=lambda name: -spread[name])
    return [*parts, names[0]] if names else []


def tutor_pose(motion: Motion) -> dict[str, Any]:
    """World positions of every tutor frame, flattened [frame][joint][xyz], rounded to 0.1 mm
    of a centimetre rig (file units, 2 decimals), with the skeleton's parents."""
    points = positions(motion)
    return {
        "parents": [int(p) for p in motion.skeleton.parents],
        "positions": np.round(points, 2).ravel().tolist(),
    }


def plain_labels(motion: Motion) -> dict[str, str]:
    """Every joint's anatomical name ("left thigh"), for the page's lists and captions."""
    return body_parts.plain_labels(motion.skeleton)


def grammar_names(
    names: tuple[str, ...], labels: Mapping[str, str] | None = None
) -> dict[str, str]:
    """How each joint is written in a grammar: its plain words with underscores ("left_thigh";
    given ``labels``, the words of the body-part ticks, "hips" for a rig's "Waist"), or the rig's
    name where two joints would read the same or the words would be another joint's older
    spelling (its readable form, which stored rules may use)."""
    readable = {name: joint_label(name) for name in names}
    plain = {name: (labels or {}).get(name, readable[name]).replace(" ", "_") for name in names}
    counts = Counter(plain.values())
    return {
        name: words
        if counts[words] == 1
        and _WRITABLE.fullmatch(words)
        and all(readable[other] != joint_label(words) for other in names if other != name)
        else name
        for name, words in plain.items()
    }


def written_names(skeleton: Skeleton) -> dict[str, str]:
    """The rig's joints as rules write them: in the words of the body-part ticks."""
    return grammar_names(tuple(skeleton.names), body_parts.plain_labels(skeleton))


def older_names(skeleton: Skeleton) -> set[str]:
    """Spellings rules were written in before they took the ticks' words ("waist", "spine"):
    still understood, so stored rules keep working."""
    return set(grammar_names(tuple(skeleton.names)).values()) | set(skeleton.names)


def rig_grammar(text: str, skeleton: Skeleton) -> str:
    """The rules with body parts in the rig's own names, as the analysis matches them ("@hips$3"
    becomes "@Waist$3"); older spellings and the rest of the text are left as written."""
    by_words = {
        joint_label(written): rig
        for rig, written in written_names(skeleton).items()
        if _WRITABLE.fullmatch(rig)
    }
    taken = {joint_label(rig) for rig in skeleton.names}
    return rename_joints(
        text,
        lambda joint: (
            joint if joint_label(joint) in taken else by_words.get(joint_label(joint), joint)
        ),
    )


def type_names(exercise) -> dict[int, str]:
    """Names of the exercise's kinds of key pose, with plain words for those nobody named."""
    kinds = set(exercise.tutor_landmark_types or [1, 2]) | {1}
    named = exercise.landmark_type_names or {}
    return {
        int(t): str(named.get(str(t)) or ("start" if t == 1 else key_pose_name(t, named)))
        for t in sorted(kinds)
    }


def grammar_joints(exercise, motion: Motion, order: list[str]) -> list[str]:
    """The joints a new exercise's grammar speaks of: those the therapist ticked, else those
    whose pose differs between the marked key poses (as the model build picks them), else the
    ones that move most."""
    if exercise.involved_joints:
        return list(exercise.involved_joints)
    try:
        return moving_joints(motion, exercise.tutor_landmark_frames, exercise.tutor_landmark_types)
    except (ValueError, IndexError, KeyError):  # too few key poses marked yet
        return order[:DEFAULT_GRAMMAR_JOINTS]


def default_grammar_text(exercise, motion: Motion, order: list[str]) -> str:
    joints = grammar_joints(exercise, motion, order) or order[:DEFAULT_GRAMMAR_JOINTS]
    written = written_names(motion.skeleton)
    return default_grammar([written.get(j, j) for j in joints], type_names(exercise))


def grammar_has_findings() -> bool:
    """Whether the grammar speaks of whole-recording findings (``%less$knee_flexion_left``), so
    the page's guide explains them only when the parser takes them."""
    try:
        Grammar.parse('%less$knee_flexion_left -> F:"Bend your left knee more"')
    except GrammarError:
        return False
    return True
