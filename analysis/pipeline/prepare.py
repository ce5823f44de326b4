"""First stages of the pipeline: check the recording, map its joints, match the tutor's frame rate,
and compute the pose features the later stages share."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion, RecordingTooShortError, Skeleton, map_joints
from analysis.bvh.plausibility import DEFAULT_LIMITS, Limits, check_recording, distinct_durations
from analysis.clinical.body import Body, find_body
from analysis.kinematics import (
    Kinematics,
    flatten,
    joint_angles,
    kinematics,
    map_onto,
    resample,
    scaled_positions,
)
from analysis.landmarks import ProgressAxis

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Prepared:
    """The recording at the model's frame rate, with its joints in the model's order.

    ``points``: (F, J, 3) scaled, root-relative, heading-normalised positions; ``local_q``:
    (F, J, 4) local rotations; ``angles``: {model joint name: (F,) degrees}; ``kinematics``:
    the one forward-kinematics pass of ``motion`` (its own joint order), which every later stage
    reads; ``body``: the rig's body parts (`analysis.clinical.body.find_body`), found once.
    """

    motion: Motion
    joint_index: list[int]
    points: FloatArray
    local_q: FloatArray
    angles: dict[str, FloatArray]
    kinematics: Kinematics
    body: Body

    @property
    def n_frames(self) -> int:
        return int(self.points.shape[0])


def check_length(motion: Motion, rep_frames: float, model_fps: float) -> None:
    """Refuse a recording shorter than half the tutor's repetition: quick movements are real
    repetitions, so the bar follows the exercise, not a fixed time. The bar is compared in whole
    frames of the recording (rounded up, with a float tolerance): two times computed differently
    (0.633327 s and 0.633333 s) are never compared or printed as if they differed."""
    needed_frames = max(4, min_frames(0.5 * rep_frames / model_fps, motion.frame_time))
    if motion.n_frames >= needed_frames:
        return
    lasts, least = distinct_durations(motion.duration, needed_frames * motion.frame_time)
    raise RecordingTooShortError(
        f"The recording lasts {lasts} ({motion.n_frames} frames); at least {least} "
        f"({needed_frames} frames) are needed to hold one repetition."
    )


def min_frames(seconds: float, frame_time: float) -> int:
    """Frames of ``frame_time`` needed to last ``seconds``; a bar within a thousandth of a frame
    of a whole number of frames is that number (times rounded by a file's frame time)."""
    return int(np.ceil(seconds / frame_time - 1e-3))


def prepare(
    motion: Motion,
    model_names: tuple[str, ...] | Skeleton,
    fps: float,
    rep_frames: float,
    limits: Limits = DEFAULT_LIMITS,
) -> Prepared:
    """Map joints (SkeletonMismatchError if impossible), resample, compute features.

    Given the model's skeleton (``model.tutor.skeleton``) rather than its joint names, a recording
    of any rig is first put on that skeleton with `analysis.kinematics.map_onto`.
    """
    names = model_names.names if isinstance(model_names, Skeleton) else model_names
    # Before anything is mapped or resampled: a damaged header must not allocate millions of frames.
    check_recording(motion, fps, len(names), limits)
    if isinstance(model_names, Skeleton):
        motion = map_onto(motion, model_names)
        model_names = model_names.names
    mapping = map_joints(model_names, motion.skeleton.names)
    check_length(motion, rep_frames, fps)
    at_rate = resample(motion, fps)
    index = [at_rate.skeleton.names.index(mapping[n]) for n in model_names]
    kin = kinematics(at_rate)
    points = scaled_positions(at_rate, index, kin)
    own_angles = joint_angles(at_rate, kin)
    angles = {n: own_angles[mapping[n]] for n in model_names if mapping[n] in own_angles}
    local_q = in_model_order(kin.local_q, index)
    return Prepared(at_rate, index, points, local_q, angles, kin, find_body(at_rate.skeleton))


def in_model_order(values: FloatArray, index: list[int]) -> FloatArray:
    """Per-joint series (F, J, ...) with their joints in the model's order (``index``); the
    series itself when the recording already has that order (no 7 MB copy per minute)."""
    if index == list(range(values.shape[1])):
        return values
    return np.take(values, index, axis=1)  # np.take: 7× faster than [:, index] here


def mirrored(points: FloatArray, mirror: list[int]) -> FloatArray:
    """The left/right mirror image of (F, J, 3) heading-normalised positions (x is lateral)."""
    out = np.take(points, mirror, axis=1)  # a new array (np.take gathers faster than [:, i])
    out[..., 0] *= -1.0
    return out


def progress_signal(
    prepared: Prepared, axis: ProgressAxis, mirror_index: list[int]
) -> tuple[FloatArray, bool]:
    """The progress signal on the tutor's axis, from the recording or its mirror image, whichever
    moves more along it (a patient may do a one-sided exercise with the other side first)."""
    direct = axis.progress(flatten(prepared.points))
    mirror = axis.progress(flatten(mirrored(prepared.points, mirror_index)))
    spans = [float(np.percentile(s, 95) - np.percentile(s, 5)) for s in (direct, mirror)]
    use_mirror = spans[1] > 1.25 * spans[0]
    return (mirror if use_mirror else direct), use_mirror
