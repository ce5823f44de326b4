"""BVH files in and out: reader, writer, errors, joint names and body parts of other rigs.

Pipeline: the first stage reads the upload with `read`; `analysis.kinematics.map_onto` then puts
it on the exercise's skeleton using the body parts `rigs` finds (retargeting needs rotations, so
it lives in `analysis.kinematics`, above this package).
"""

from analysis.bvh.errors import (
    AnalysisInputError,
    BVHError,
    RecordingTooShortError,
    SkeletonMismatchError,
)
from analysis.bvh.io import Motion, Skeleton, dumps, read, write
from analysis.bvh.plausibility import ImplausibleRecordingError, Limits, check_recording
from analysis.bvh.skeleton_map import map_joints, normalise_name

__all__ = [
    "AnalysisInputError",
    "BVHError",
    "ImplausibleRecordingError",
    "Limits",
    "Motion",
    "RecordingTooShortError",
    "Skeleton",
    "SkeletonMismatchError",
    "check_recording",
    "dumps",
    "map_joints",
    "normalise_name",
    "read",
    "write",
]
