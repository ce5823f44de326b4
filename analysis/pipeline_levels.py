"""Per-joint assessment levels at key poses and the performance level γ.

Levels compare the patient's local joint rotation at a key pose with the tutor's mean rotation
for that key-pose type: the angle of the relative rotation (degrees) is cut at `THRESHOLDS_DEG`
into levels 1 (as the tutor) to 4. γ per joint is the exponential smoothing (factor `SMOOTHING`)
of the session's mean normalised level 1 − (level − 1) / 3, bounded to [0, 1].
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis import quaternions as quat

FloatArray = npt.NDArray[np.float64]
THRESHOLDS_DEG = (15.0, 30.0, 45.0)
SMOOTHING = 0.3
N_LEVELS = 4


def mean_rotation(q: FloatArray) -> FloatArray:
    """Mean of unit quaternions (N, J, 4) per joint: the principal eigenvector of Σ q qᵀ."""
    out = np.empty(q.shape[1:])
    for j in range(q.shape[1]):
        _, vectors = np.linalg.eigh(q[:, j].T @ q[:, j])
        out[j] = quat.canonical(vectors[:, -1])
    return out


def mean_poses(local_q: FloatArray, frames: Sequence[int], types: Sequence[int]) -> dict[int, Any]:
    """The tutor's mean local rotations per landmark type: {type: (J, 4)}."""
    out = {}
    for t in sorted(set(types)):
        chosen = [f for f, k in zip(frames, types, strict=True) if k == t]
        out[int(t)] = mean_rotation(local_q[chosen])
    return out


def tutor_mean_pose(model: Any, landmark_type: int) -> FloatArray:
    poses = model.components["mean_poses"]
    return poses.get(landmark_type, poses[min(poses)])


def joint_levels(pose: FloatArray, reference: FloatArray) -> npt.NDArray[np.int64]:
    """Level 1..4 per joint from the angle between pose (J, 4) and reference (J, 4)."""
    angle = quat.angle_between(reference, pose, degrees=True)
    return 1 + np.searchsorted(np.array(THRESHOLDS_DEG), angle, side="right").astype(np.int64)


def gamma_update(
    history: Mapping[str, float] | None, assessment: list[dict[str, Any]], joints: list[str]
) -> dict[str, float]:
    """γ per involved joint after this session (1 = performs like the tutor)."""
    out = {}
    for joint in joints:
        levels = [a["levels"][joint] for a in assessment if joint in a["levels"]]
        if not levels:
            continue
        session = 1.0 - (float(np.mean(levels)) - 1.0) / (N_LEVELS - 1)
        previous = (history or {}).get(joint)
        value = session if previous is None else (1 - SMOOTHING) * previous + SMOOTHING * session
        out[joint] = round(float(np.clip(value, 0.0, 1.0)), 4)
    return out
