"""Key poses suggested on a tutor recording before any are annotated (annotation page).

A therapist annotating a new tutor wants a starting point, not a blank timeline. Without a trained
landmark model the one thing every exercise shares is its shape: the body leaves a rest pose,
reaches the exercise's extreme pose and comes back. So the suggestion follows the whole-body
distance from the first frame's pose: its prominent maxima are extreme poses (type 2), the lowest
frame between two extremes and the stretches before the first and after the last are rest poses
(type 1). The therapist then moves, retypes or deletes them.

A take often holds something else besides the exercise at its start or end: a lifter walks the bar
out of the rack and back into it, a patient turns to the camera. Such a movement stands out from
rest as well, but it is not the exercise's extreme pose: the first or the last extreme is dropped
when it both falls short of the others (under `SHORT_REACH` of their median distance from rest) and
ends in another pose than they do (its distance from their typical extreme pose over
`OTHER_POSE` times its distance from rest). On the squat video of the capture samples the bar's
racking reaches 0.53 of the squats with a pose 2.1 times further from their bottom than from
standing. Of UI-PRMD's 140 sessions (10 repetitions each) it changes one: m03 s04 correct, whose
first of 12 extremes it drops (measured 2026-11-29; the 91 sessions given 10 stay so).
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import numpy.typing as npt
from scipy.signal import find_peaks

from analysis.bvh import Motion
from analysis.landmarks.key_poses import KeyPoses
from analysis.landmarks.signature import pose_series

REST_TYPE = 1
EXTREME_TYPE = 2
SHORT_REACH = 0.75  # of the extremes' median distance from rest
OTHER_POSE = 1.5  # distance from the typical extreme pose, over the distance from rest


def distance_from_start(motion: Motion) -> npt.NDArray[np.float64]:
    """(F,) mean joint distance (cm) of each frame's normalised pose from the first frame's."""
    return _from_first(pose_series(motion))


def _from_first(poses: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    return np.asarray(np.linalg.norm(poses - poses[0], axis=2).mean(axis=1), dtype=np.float64)


def the_exercise_extremes(
    poses: npt.NDArray[np.float64], distance: npt.NDArray[np.float64], extremes: np.ndarray
) -> np.ndarray:
    """``extremes`` without a first or last one of another movement (see the module docstring):
    short of the others' reach and far from their typical extreme pose."""
    if extremes.size < 3:  # two say nothing about which one is typical
        return extremes
    reach = distance[extremes]
    typical = np.median(poses[extremes], axis=0)
    elsewhere = np.linalg.norm(poses[extremes] - typical, axis=2).mean(axis=1)
    other = (reach < SHORT_REACH * float(np.median(reach))) & (elsewhere > OTHER_POSE * reach)
    other[1:-1] = False  # within the take, between two of the exercise's: the exercise's own
    return extremes[~other]


def extreme_frames(distance: npt.NDArray[np.float64], fps: float, prominence: float) -> np.ndarray:
    """Frames of the prominent maxima of ``distance``, at least 0.3 s apart."""
    span = float(distance.max() - distance.min())
    if span <= 1e-9:
        return np.zeros(0, dtype=np.int64)
    peaks, _ = find_peaks(distance, prominence=prominence * span, distance=max(1, round(0.3 * fps)))
    return peaks.astype(np.int64)


def rest_frames(distance: npt.NDArray[np.float64], extremes: np.ndarray) -> list[int]:
    """The lowest frame before the first extreme, between each pair, and after the last."""
    edges = [0, *extremes.tolist(), distance.shape[0] - 1]
    return [start + int(np.argmin(distance[start : stop + 1])) for start, stop in pairwise(edges)]


def suggest_key_poses(motion: Motion, prominence: float = 0.3) -> KeyPoses:
    """Suggested key-pose frames and types (1 rest, 2 extreme) in time order.

    ``prominence`` is the share of the distance curve's range a maximum must stand out by to
    count as an extreme pose; 0.3 keeps tremor and pauses from adding poses.
    """
    poses = pose_series(motion)
    distance = _from_first(poses)
    extremes = the_exercise_extremes(
        poses, distance, extreme_frames(distance, motion.fps, prominence)
    )
    if extremes.size == 0:
        return KeyPoses.of([], [])
    marked = {frame: REST_TYPE for frame in rest_frames(distance, extremes)}
    marked.update({int(frame): EXTREME_TYPE for frame in extremes})
    frames = sorted(marked)
    return KeyPoses.of(frames, [marked[f] for f in frames])
