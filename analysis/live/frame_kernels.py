"""A live frame's features in one compiled call: the stream's rotations and positions, the model's
joints facing the first frame's heading, the progress along the tutor's axis as performed and
mirrored, and the quaternion features the aligners and guidance compare.

Per frame these are a dozen numpy calls on a few dozen numbers each, where the call costs more
than the arithmetic. The kernel runs the forward-kinematics kernels the whole-motion code runs
(`analysis.kinematics.forward_kinematics`) and the same products (numba's ``@`` calls the BLAS
numpy calls, so the values are numpy's bit for bit: `tests/live/test_compiled_live.py`).
"""

from __future__ import annotations

from typing import NamedTuple

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.kinematics.forward_kinematics import _euler_quaternions, _positions_only

FloatArray = npt.NDArray[np.float64]
IndexArray = npt.NDArray[np.intp]
MIRROR_Q = np.array([1.0, 1.0, -1.0, -1.0])  # (w, x, y, z) reflected in the lateral (x) axis
MIRROR_X = np.array([-1.0, 1.0, 1.0])  # a position reflected in the lateral (x) axis


class FeatureLayout(NamedTuple):
    """What the kernel needs of the stream's skeleton and the exercise model, made once."""

    columns: npt.NDArray[np.int64]  # rotation channels of each stream joint
    axes: npt.NDArray[np.int64]
    layout: npt.NDArray[np.int64]  # rotation columns, axes, translation columns (J, 9)
    offsets: FloatArray
    parents: npt.NDArray[np.int64]
    model_rows: IndexArray  # the stream joint of each of the model's
    mirror: IndexArray  # each model joint's mirror image
    start_pose: FloatArray  # the progress axis (`ProgressAxis`)
    direction: FloatArray
    direct: IndexArray  # stream rows of the aligned joints
    flipped: IndexArray  # their mirror images
    gesture: IndexArray  # the joints guidance aligns
    gesture_mirror: IndexArray


class FrameStore:
    """Every model-rate frame's features so far, in arrays that grow by doubling: the kernel
    writes frame t's row in place, so a frame costs one call and no new arrays."""

    def __init__(self, lay: FeatureLayout, n_model_joints: int, capacity: int = 256) -> None:
        self.lay, self.t = lay, 0
        d, g = 4 * lay.direct.size, lay.gesture.size
        self.q = np.empty((2, capacity, d))  # aligned joints' quaternions, as performed / mirrored
        self.gesture = np.empty((2, capacity, g, 4))  # guidance's joints / their mirror images
        self.model_pos = np.empty((n_model_joints, 3))  # the newest frame's (for display)

    def add(self, values: FloatArray, undo: FloatArray, scale: float) -> tuple[float, float]:
        """Frame t's features from its channel values (C,), C-contiguous float64: stored, and
        its progress along the tutor's axis as performed and mirrored returned. ``undo`` (3, 3)
        turns row vectors to face the first frame's heading over the body's size, ``scale``:
        the progress axis's."""
        if self.t == self.q.shape[1]:
            self.q = _doubled(self.q)
            self.gesture = _doubled(self.gesture)
        lay = self.lay
        progress = _features(values, *lay, undo, scale, MIRROR_Q, MIRROR_X, self.t, self.q,
                             self.gesture, self.model_pos)  # fmt: skip
        self.t += 1
        return progress


def _doubled(a: FloatArray) -> FloatArray:
    out = np.empty((a.shape[0], 2 * a.shape[1], *a.shape[2:]))
    out[:, : a.shape[1]] = a
    return out


@nb.njit(cache=True, nogil=True)
def _features(  # noqa: PLR0917 - numba functions take positional arguments only
    values: FloatArray, columns: npt.NDArray[np.int64], axes: npt.NDArray[np.int64],
    layout: npt.NDArray[np.int64], offsets: FloatArray, parents: npt.NDArray[np.int64],
    index: IndexArray, mirror: IndexArray, start_pose: FloatArray, direction: FloatArray,
    direct: IndexArray, flipped: IndexArray, gesture: IndexArray, gesture_mirror: IndexArray,
    undo: FloatArray, scale: float, mirror_q: FloatArray, mirror_x: FloatArray, t: int,
    q_out: FloatArray, gesture_out: FloatArray, pos_out: FloatArray,
) -> tuple[float, float]:  # fmt: skip
    frame = values.reshape((1, values.size))
    rot = _euler_quaternions(frame, columns, axes)[0]
    pos = _positions_only(frame, layout, offsets, parents)[0]
    model_pos = pos[index]
    pos_out[:] = model_pos
    points = (model_pos - pos[0]) @ undo
    sides = np.empty((2, points.size))
    sides[0] = points.ravel()
    sides[1] = (points[mirror] * mirror_x).ravel()
    progress = (sides - start_pose) @ direction / scale
    q_out[0, t] = rot[direct].ravel()
    q_out[1, t] = (rot[flipped] * mirror_q).ravel()
    gesture_out[0, t] = rot[gesture]
    gesture_out[1, t] = rot[gesture_mirror]
    return progress[0], progress[1]
