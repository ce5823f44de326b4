"""Fitting the parts of an exercise model from the tutor (and labelled recordings).

Kept apart from `analysis.model` (the container and its file format) so that each fitted part is
one small function: involved joints, progress axis, repetition templates, score calibration.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion
from analysis.kinematics import rotations
from analysis.pipeline_levels import mean_poses
from analysis.posefeatures import flatten, relative_to_start, scaled_positions
from analysis.scoring import ScoreScale, calibrate_scale, repetition_distance
from analysis.segmentation import fit_axis

FloatArray = npt.NDArray[np.float64]
Progress = Callable[[str, float], None]


@dataclass(frozen=True, eq=False)
class TrainingRecording:
    """A therapist-labelled recording: key poses and a label ('correct', 'incorrect' or 1..4)."""

    motion: Motion
    landmark_frames: tuple[int, ...]
    landmark_types: tuple[int, ...]
    label: str


def mirror_permutation(names: Sequence[str]) -> list[int]:
    """For each joint, the index of its left/right counterpart (itself when it has none)."""
    index = {n: k for k, n in enumerate(names)}
    out = []
    for name in names:
        swapped = name.replace("Left", "\0").replace("Right", "Left").replace("\0", "Right")
        out.append(index.get(swapped, index[name]))
    return out


def moving_joints(points: FloatArray, names: Sequence[str], share: float = 0.35) -> list[str]:
    """Joints whose (root-relative) movement is at least ``share`` of the largest, in file order."""
    spread = np.linalg.norm(points.std(axis=0), axis=-1)
    spread[0] = 0.0  # the root is the origin of root-relative positions
    keep = spread >= share * spread.max() if spread.max() > 0 else spread >= 0
    return [n for n, k in zip(names, keep, strict=True) if k]


def tutor_repetitions(frames: Sequence[int], types: Sequence[int]) -> list[tuple[int, int]]:
    """(start, end) of each tutor repetition: from one type-1 landmark to the frame before the next."""
    starts = [f for f, t in zip(frames, types, strict=True) if t == 1]
    return [(a, max(b - 1, a)) for a, b in zip(starts[:-1], starts[1:], strict=True)]


def templates(features: FloatArray, reps: list[tuple[int, int]]) -> list[FloatArray]:
    """Each tutor repetition's movement relative to its starting pose: list of (n_k, D)."""
    return [relative_to_start(features[a : b + 1]) for a, b in reps]


def _end_of_range(frames: Sequence[int], types: Sequence[int]) -> npt.NDArray[np.int64]:
    return np.array([f for f, t in zip(frames, types, strict=True) if t != 1], dtype=np.int64)


def fit_components(
    tutor: Motion,
    frames: list[int],
    types: list[int],
    joints: Sequence[str] | None,
    training: Sequence[Any],
    on_progress: Progress | None,
) -> tuple[dict[str, Any], list[str], dict[str, Any]]:
    """Fit every part; returns (components, involved joint names, training report)."""
    report = on_progress or (lambda stage, fraction: None)
    names = tutor.skeleton.names
    all_points = scaled_positions(tutor, list(range(len(names))))
    involved = list(joints) if joints else moving_joints(all_points, names)
    unknown = sorted(set(involved) - set(names))
    if unknown:
        raise ValueError(f"the tutor has no joint named {', '.join(unknown)}")
    report("features", 0.2)
    reps = tutor_repetitions(frames, types)
    if not reps:
        raise ValueError("the tutor needs at least two type-1 landmarks (one whole repetition)")
    starts = np.array([a for a, _ in reps], dtype=np.int64)
    axis = fit_axis(flatten(all_points), starts, _end_of_range(frames, types))
    involved_idx = [names.index(n) for n in involved]
    movement = flatten(all_points[:, involved_idx])
    tutor_templates = templates(movement, reps)
    report("calibration", 0.5)
    scale = calibrate_scale(tutor_templates, training_distances(training, tutor_templates, involved))
    components = {
        "axis": axis,
        "mirror": mirror_permutation(names),
        "involved_index": involved_idx,
        "templates": tutor_templates,
        "score_scale": scale,
        "tutor_reps": reps,
        "mean_poses": mean_poses(rotations(tutor), frames, types),
    }
    report("done", 1.0)
    return components, involved, {"tutor_repetitions": len(reps), "score_scale": scale.as_dict()}


def training_distances(
    training: Sequence[TrainingRecording], tutor_templates: list[FloatArray], involved: list[str]
) -> list[tuple[float, bool]]:
    """(distance to the tutor, is correct) for every repetition of the labelled recordings."""
    out: list[tuple[float, bool]] = []
    for item in training:
        names = item.motion.skeleton.names
        feats = flatten(scaled_positions(item.motion, [names.index(n) for n in involved]))
        correct = item.label in ("correct", "1")
        for a, b in tutor_repetitions(item.landmark_frames, item.landmark_types):
            segment = relative_to_start(feats[a : b + 1])
            out.append((repetition_distance(segment, tutor_templates), correct))
    return out


__all__ = ["ScoreScale", "TrainingRecording", "fit_components", "mirror_permutation"]
