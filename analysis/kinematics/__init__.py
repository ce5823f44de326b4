"""Geometry of a motion: quaternions, forward kinematics, resampling, normalised pose features,
and retargeting a recording of another rig onto an exercise's skeleton (`map_onto`).

Pipeline: preparation puts the upload on the exercise's skeleton (`map_onto`), resamples it to
the tutor's frame rate and computes the rotations and normalised positions every later stage reads.
"""

from analysis.kinematics.forward_kinematics import (
    Kinematics,
    forward,
    joint_angles,
    kinematics,
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
from analysis.kinematics.retarget import map_onto

__all__ = [
    "Kinematics",
    "flatten",
    "forward",
    "joint_angles",
    "kinematics",
    "map_onto",
    "normalised_positions",
    "positions",
    "range_of_motion",
    "relative_to_start",
    "resample",
    "rotations",
    "scaled_positions",
    "translations",
]
