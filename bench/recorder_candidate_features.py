"""Third-round candidates for `bench.eval_recorder_candidates` (issue 35, item 2): ways to make a
Kinect take and its Vicon pair score alike that do not widen the score's unit.

- shoulders (and head) carried by the trunk: each recorder's shoulder joints put back where the
  trunk carries them (the take's median place in the trunk's frame), since Vicon's shoulder
  centres follow the shoulder girdle and the Kinect's barely do;
- Vicon seen at the Kinect's bandwidth: a Gaussian low-pass on Vicon takes (and tutors) only;
- per-joint losses left out: a joint that jumps farther than a body moves in a frame, within a
  repetition, is left out of that repetition's mean over joints (on either recorder's side);
- one joint's excess capped, or the worst joint left out of the mean: a lost limb counts as
  much as a few units, not tens;
- the recording's score as the median of its repetitions' scores rather than their mean.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from scipy.ndimage import gaussian_filter1d

from analysis.clinical.body import Body

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
JUMP_SPEED = 1.5  # body sizes a second (about 5 m/s): no joint of these exercises moves faster
HELD_SPEED = 0.05  # body sizes a second: a joint this still before a jump was held, not moving
KINECT_SIGMA = 0.05  # seconds: the Gaussian that takes Vicon's trajectories to a Kinect's bandwidth


def bridge_jumps(points: FloatArray, fps: float) -> tuple[FloatArray, int]:
    """(F, J, 3) with jumps bridged, and how many joint-frames were bridged."""
    out = points.astype(np.float64, copy=True)
    speed = np.linalg.norm(np.diff(out, axis=0), axis=-1) * fps  # (F - 1, J)
    count = 0
    for joint in range(out.shape[1]):
        lost = np.zeros(out.shape[0], dtype=bool)
        for frame in np.flatnonzero(speed[:, joint] > JUMP_SPEED) + 1:
            lost[frame] = True
            held = frame - 1
            while held > 0 and speed[held - 1, joint] < HELD_SPEED:
                lost[held] = True
                held -= 1
        if lost.any() and not lost.all():
            good = np.flatnonzero(~lost)
            for axis in range(3):
                out[lost, joint, axis] = np.interp(
                    np.flatnonzero(lost), good, out[good, joint, axis]
                )
            count += int(lost.sum())
    return out, count


def unit(v: FloatArray) -> FloatArray:
    return np.asarray(v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9))


def trunk_frames(points: FloatArray, body: Body) -> FloatArray:
    """(F, 3, 3): columns forward, up (pelvis → neck) and the hip line made perpendicular."""
    joints = body.joints
    up = unit(points[:, joints.get("neck", joints.get("chest", 0))] - points[:, joints["pelvis"]])
    side = points[:, joints["hip_right"]] - points[:, joints["hip_left"]]
    side = unit(side - np.sum(side * up, axis=-1, keepdims=True) * up)
    return np.stack((np.cross(up, side), up, side), axis=-1)


def chest_frames(points: FloatArray, body: Body) -> FloatArray:
    """(F, 3, 3): the trunk's frame, columns forward, up (pelvis → chest) and the hip line made
    perpendicular to it; the shoulders are left out of it since they are what it carries."""
    joints = body.joints
    up = unit(points[:, joints["chest"]] - points[:, joints["pelvis"]])
    side = points[:, joints["hip_right"]] - points[:, joints["hip_left"]]
    side = unit(side - np.sum(side * up, axis=-1, keepdims=True) * up)
    return np.stack((np.cross(up, side), up, side), axis=-1)


def carried(points: FloatArray, body: Body, names: tuple[str, ...]) -> FloatArray:
    """(F, J, 3) with the joints ``names`` put where the trunk carries them: their median place
    over the take in the trunk's frame, about the chest."""
    out = points.astype(np.float64, copy=True)
    frames = chest_frames(out, body)
    chest = out[:, body.joints["chest"]]
    for name in (n for n in names if n in body.joints):  # a Vicon rig has no collars
        joint = body.joints[name]
        local = np.einsum("fij,fi->fj", frames, out[:, joint] - chest)  # frame^T · offset
        place = np.median(local, axis=0)
        out[:, joint] = chest + np.einsum("fij,j->fi", frames, place)
    return out


def low_passed(points: FloatArray, fps: float, sigma_s: float = KINECT_SIGMA) -> FloatArray:
    """(F, J, 3) smoothed along time by a Gaussian of ``sigma_s`` seconds."""
    return np.asarray(gaussian_filter1d(points, sigma_s * fps, axis=0, mode="nearest"))


def jumping_joints(points: FloatArray, fps: float, limit: float) -> BoolArray:
    """(J,) the joints that somewhere in (F, J, 3) move faster than ``limit`` body sizes a second
    (root-relative: a body part does not travel that far in a frame; the tracker lost it)."""
    if len(points) < 2:
        return np.zeros(points.shape[1], dtype=bool)
    speed = np.linalg.norm(np.diff(points, axis=0), axis=-1) * fps
    return np.asarray(speed.max(axis=0) > limit)


def capped_mean(over: FloatArray, cap: float) -> float:
    """The mean over joints of each joint's excess (in score units), each capped at ``cap``."""
    return float(np.mean(np.minimum(over, cap)))


def trimmed_mean(over: FloatArray, left_out: int) -> float:
    """The mean over joints of the excess with the ``left_out`` worst joints left out."""
    kept = np.sort(over)[: max(1, over.size - left_out)]
    return float(np.mean(kept))
