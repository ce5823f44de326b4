"""Forward kinematics of one streamed frame at a time.

`analysis.kinematics` works on whole motions: every call reads the skeleton's channel layout
again and memoises per motion, which costs more than the arithmetic for a single frame. A live
session reads the layout once and runs the same compiled kernels on each frame.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from analysis.bvh import Skeleton
from analysis.kinematics import forward_kinematics as fk

FloatArray = npt.NDArray[np.float64]


class FrameKinematics:
    """Local rotations (J, 4) and world positions (J, 3) of one frame of ``skeleton``."""

    def __init__(self, skeleton: Skeleton) -> None:
        if np.any(skeleton.parents >= np.arange(len(skeleton.names))):
            raise ValueError("every joint's parent must come before it")
        # the skeleton's layout for the compiled kernels (a live session's kernel takes them)
        self.columns, self.axes = fk._rotation_layout(skeleton)
        self.layout = np.hstack([self.columns, self.axes, fk._translation_columns(skeleton)])
        self.offsets = np.ascontiguousarray(skeleton.offsets, dtype=np.float64)
        self.parents = np.ascontiguousarray(skeleton.parents, dtype=np.int64)

    def rotations(self, frames: FloatArray) -> FloatArray:
        """(F, J, 4) local rotations of (F, C) channel values."""
        return fk._euler_quaternions(np.ascontiguousarray(frames), self.columns, self.axes)

    def positions(self, frames: FloatArray) -> FloatArray:
        """(F, J, 3) world positions of (F, C) channel values."""
        data = np.ascontiguousarray(frames, dtype=np.float64)
        return fk._positions_only(data, self.layout, self.offsets, self.parents)
