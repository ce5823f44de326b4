"""BVH files in and out: reader, writer, errors, and the map from other rigs' joint names.

Pipeline: the first stage reads the upload with `read` and maps its joints with `map_joints`.
"""

from analysis.bvh.errors import (
    AnalysisInputError,
    BVHError,
    RecordingTooShortError,
    SkeletonMismatchError,
)
from analysis.bvh.io import Motion, Skeleton, dumps, read, write
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
    "normalise_name",
    "read",
    "write",
]
