"""Resampling a motion to another frame rate: slerp for rotations, linear for positions.

Joints with three rotation channels are interpolated as quaternions (the shortest arc between
neighbouring frames) and written back as Euler angles in the joint's own channel order, unwrapped so
that angles stay continuous. Position channels, and joints with fewer than three rotation channels
(whose rotations are about fixed axes), are interpolated linearly channel by channel.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from analysis.bvh.io import Motion
from analysis.kinematics import quaternions as quat
from analysis.kinematics.forward_kinematics import rotations

FloatArray = npt.NDArray[np.float64]


def sample_times(n_frames: int, frame_time: float, fps: float) -> FloatArray:
    """Times (s) of the new frames covering the original duration: (F',)."""
    duration = (n_frames - 1) * frame_time
    count = int(np.floor(duration * fps + 1e-9)) + 1
    return np.arange(count) / fps


def _linear(frames: FloatArray, source: FloatArray, target: FloatArray) -> FloatArray:
    out = np.empty((target.size, frames.shape[1]))
    for column in range(frames.shape[1]):
        out[:, column] = np.interp(target, source, frames[:, column])
    return out


def full_rotation_joints(motion: Motion) -> list[tuple[int, list[int], str]]:
    """Joints with three rotation channels: (joint, their frame columns, Euler order)."""
    joints = []
    skeleton = motion.skeleton
    for joint, (start, channels) in enumerate(
        zip(skeleton.channel_starts, skeleton.channels, strict=True)
    ):
        cols = [int(start) + k for k, c in enumerate(channels) if c.endswith("rotation")]
        if len(cols) == 3:
            order = "".join(channels[c - int(start)][0] for c in cols)
            joints.append((joint, cols, order))
    return joints


def _slerped(local_q: FloatArray, position: FloatArray) -> FloatArray:
    """Quaternions at fractional frame positions (F',) from (F, J, 4): (F', J, 4)."""
    q = quat.make_continuous(local_q, axis=0)
    below = np.clip(np.floor(position).astype(int), 0, q.shape[0] - 1)
    above = np.minimum(below + 1, q.shape[0] - 1)
    t = np.broadcast_to((position - below)[:, None], (position.size, q.shape[1]))
    return quat.slerp(q[below], q[above], t)


def resample(motion: Motion, fps: float) -> Motion:
    """The motion at ``fps`` frames per second over the same duration (first frame kept)."""
    if fps <= 0:
        raise ValueError("fps must be positive")
    if motion.n_frames < 2 or abs(motion.fps - fps) < 1e-9 * fps:
        return motion
    source = np.arange(motion.n_frames, dtype=np.float64) * motion.frame_time
    target = sample_times(motion.n_frames, motion.frame_time, fps)
    frames = _linear(motion.frames, source, target)
    full = full_rotation_joints(motion)
    if full:
        joint_ids = [j for j, _, _ in full]
        slerped = _slerped(rotations(motion)[:, joint_ids], target / motion.frame_time)
        for k, (_, cols, order) in enumerate(full):
            angles = quat.to_euler(slerped[:, k], order)
            frames[:, cols] = _unwrap_towards(angles, frames[:, cols])
    return motion.with_frames(np.asarray(frames, dtype=np.float64), 1.0 / fps)


def _unwrap_towards(angles: FloatArray, reference: FloatArray) -> FloatArray:
    """Shift by whole turns so each angle lies nearest the linearly interpolated original."""
    return angles + 360.0 * np.round((reference - angles) / 360.0)
