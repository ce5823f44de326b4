"""Recordings with a known mistake, for paper 001's guidance types: a correct session re-timed
(×0.6 is quicker: "too fast"; ×1.6 slower: "too slow") or with every joint's movement scaled
relative to the session's first pose (×0.6 falls short: "incomplete"; ×1.3 goes beyond the
reference: "overdone")."""

from __future__ import annotations

import numpy as np

from analysis.bvh import Motion
from analysis.kinematics import quaternions as quat
from analysis.kinematics import resample, rotations
from analysis.kinematics.resample import full_rotation_joints

EXPECTED = {
    ("tempo", 0.6): "too fast",
    ("tempo", 1.6): "too slow",
    ("range", 0.6): "incomplete",
    ("range", 1.3): "overdone",
}


def retimed(motion: Motion, factor: float) -> Motion:
    """The same movement lasting ``factor`` times as long, at the original frame rate."""
    stretched = motion.with_frames(motion.frames, motion.frame_time * factor)
    return resample(stretched, motion.fps)


def range_scaled(motion: Motion, factor: float) -> Motion:
    """Every joint's rotation away from its first-frame rotation scaled by ``factor`` (angle
    about the same axis); the root's translation is kept."""
    q = quat.make_continuous(rotations(motion), axis=0)
    rest = q[:1]
    relative = quat.multiply(quat.conjugate(rest), q)
    scaled = quat.multiply(rest, quat.from_rotvec(factor * quat.to_rotvec(relative)))
    frames = motion.frames.copy()
    for joint, cols, order in full_rotation_joints(motion):
        angles = quat.to_euler(scaled[:, joint], order)
        frames[:, cols] = angles + 360.0 * np.round((frames[:, cols] - angles) / 360.0)
    return motion.with_frames(frames)


def modified(motion: Motion, kind: str, factor: float) -> Motion:
    return retimed(motion, factor) if kind == "tempo" else range_scaled(motion, factor)
