"""Recordings with a mistake made on purpose for the corrections (issue 26), beside
`tests.analysis.guidance_cases` (re-timed, range scaled): one arm kept down, the trunk leaned
forward all through. Rotation channels are edited; the rig's names are UI-PRMD's (``Spine``,
``LeftUpperLeg``, ``Right…`` arm joints)."""

from __future__ import annotations

import numpy as np

from analysis.bvh import Motion
from analysis.clinical import angle_series
from analysis.kinematics import quaternions as quat
from analysis.kinematics import rotations
from analysis.kinematics.resample import full_rotation_joints

LEAN_DEG = 20.0


def _local(motion: Motion) -> np.ndarray:
    return quat.make_continuous(rotations(motion), axis=0)


def _with_rotations(motion: Motion, q: np.ndarray, joints: set[int] | None = None) -> Motion:
    """The motion with the (F, J, 4) local rotations ``q`` written back into its channels."""
    frames = motion.frames.copy()
    for joint, cols, order in full_rotation_joints(motion):
        if joints is None or joint in joints:
            angles = quat.to_euler(q[:, joint], order)
            frames[:, cols] = angles + 360.0 * np.round((frames[:, cols] - angles) / 360.0)
    return motion.with_frames(frames)


def arm_down(motion: Motion, side: str) -> Motion:
    """The ``side`` arm's joints held in their first-frame rotation all through."""
    names = motion.skeleton.names
    legs = ("Leg", "Foot", "Toes")
    arm = {i for i, n in enumerate(names) if n.startswith(side) and not n.endswith(legs)}
    q = _local(motion)
    q[:, sorted(arm)] = q[:1, sorted(arm)]
    return _with_rotations(motion, q, arm)


def leaned(motion: Motion, degrees: float) -> Motion:
    """The spine's rotation turned ``degrees`` about the pelvis's left-right axis (its hips'
    offsets) in every frame: the whole trunk tilts by that much against the pelvis."""
    skeleton = motion.skeleton
    names = list(skeleton.names)
    spine = names.index("Spine")
    lateral = skeleton.offsets[names.index("RightUpperLeg")] - skeleton.offsets[
        names.index("LeftUpperLeg")]  # fmt: skip
    lateral = lateral / np.linalg.norm(lateral)
    turn = quat.from_rotvec(np.radians(degrees) * lateral)
    q = _local(motion)
    q[:, spine] = quat.multiply(turn[None], q[:, spine])
    return _with_rotations(motion, q, {spine})


def trunk_flexion(motion: Motion) -> float:
    """The median trunk flexion of a motion (degrees), NaN when it cannot be measured."""
    series = angle_series(motion).get("trunk_flexion")
    return float(np.nanmedian(series)) if series is not None else float("nan")


def forward_lean(motion: Motion) -> tuple[Motion, float]:
    """The motion leaned `LEAN_DEG` forward (whichever sign of turn is forward on this rig) and
    the change of its median trunk flexion (the truth of the amount)."""
    before = trunk_flexion(motion)
    changed = leaned(motion, LEAN_DEG)
    if trunk_flexion(changed) < before:
        changed = leaned(motion, -LEAN_DEG)
    return changed, trunk_flexion(changed) - before
