"""Pose features shared by segmentation, scoring and range-of-motion figures.

Positions are made comparable across people: root-relative, turned to a common heading and divided
by the body's size (so a tall and a short patient doing the same movement give the same numbers).
Scoring works on the movement *relative to the starting pose of each repetition*: absolute
posture mostly measures body build, not how the exercise was done.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from analysis.bvh.io import Motion
from analysis.kinematics import point_kernels
from analysis.kinematics.forward_kinematics import Kinematics, normalised_positions

FloatArray = npt.NDArray[np.float64]


def body_scale(points: FloatArray, parents: npt.NDArray[np.int64]) -> float:
    """The median over frames of the summed bone lengths: one number per recording."""
    child = np.flatnonzero(parents >= 0).astype(np.int64)
    points = np.ascontiguousarray(points, dtype=np.float64)
    bones = point_kernels.distances(points, child, parents[child].astype(np.int64))
    scale = float(np.median(bones.sum(axis=1)))
    return scale if scale > 1e-9 else 1.0


def scaled_positions(
    motion: Motion, joints: list[int], kin: Kinematics | None = None
) -> FloatArray:
    """Root-relative, heading-normalised positions of ``joints`` over body size: (F, len, 3);
    ``kin``: the motion's `kinematics` when already computed."""
    points = normalised_positions(motion) if kin is None else kin.facing
    scale = body_scale(points, motion.skeleton.parents)
    if list(joints) == list(range(points.shape[1])):  # every joint in file order: no gather
        return points / scale
    return np.take(points, joints, axis=1) / scale


def flatten(points: FloatArray) -> FloatArray:
    """(F, J, 3) → (F, 3J) feature rows."""
    return points.reshape(points.shape[0], -1)


def relative_to_start(features: FloatArray) -> FloatArray:
    """Feature rows minus the first row: the movement made since the repetition began."""
    return features - features[:1]


def range_of_motion(angles: dict[str, FloatArray], joints: list[str]) -> dict[str, float]:
    """Per joint, the span (degrees) between the 5th and 95th percentile of its angle."""
    out = {}
    for name in joints:
        if name in angles and angles[name].size:
            low, high = np.percentile(angles[name], [5.0, 95.0])
            out[name] = round(float(high - low), 2)
    return out
