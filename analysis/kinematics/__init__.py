"""Geometry of a motion: quaternions, forward kinematics, resampling and normalised pose features.

Pipeline: preparation resamples to the tutor's frame rate and computes the rotations and
normalised positions every later stage reads.
"""

from analysis.kinematics.forward_kinematics import (
    forward,
    joint_angles,
    normalised_positions,
    positions,
    rotations,
    translations,
)
from analysis.kinematics.posefeatures import (
    flatten,
    range_of_motion,
    relative_to_start,
    scaled_positions,
)
from analysis.kinematics.resample import resample

__all__ = [
    "flatten",
    "forward",
    "joint_angles",
    "normalised_positions",
    "positions",
    "range_of_motion",
    "relative_to_start",
    "resample",
    "rotations",
    "scaled_positions",
    "translations",
]
