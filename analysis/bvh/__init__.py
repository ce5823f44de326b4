"""BVH files in and out: reader, writer, errors, and mapping other rigs onto an exercise skeleton.

Pipeline: the first stage reads the upload with `read` and puts it on the exercise's skeleton with
`map_onto` (same rig: unchanged; another rig: matched by body parts and retargeted).
"""

from analysis.bvh.errors import (
    AnalysisInputError,
    BVHError,
    RecordingTooShortError,
    SkeletonMismatchError,
)
from analysis.bvh.io import Motion, Skeleton, dumps, read, write
from analysis.bvh.retarget import map_onto
from analysis.bvh.skeleton_map import map_joints, normalise_name

__all__ = [
    "AnalysisInputError",
    "BVHError",
    "Motion",
    "RecordingTooShortError",
    "Skeleton",
    "SkeletonMismatchError",
    "dumps",
    "map_joints",
    "map_onto",
    "normalise_name",
    "read",
    "write",
]
