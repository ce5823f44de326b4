"""Playback payload of one analysis run: a small JSON description and raw float32 positions.

The worker stores per-frame world positions in the run's ``.npz``; the browser receives them as
little-endian float32 laid out ``[skeleton][frame][joint][xyz]`` so it never parses BVH.
Skeletons the run does not have (older runs, or before the lead adds them) are left out.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from analysis.kinematics.forward_kinematics import segment_angles
from analysis.pipeline import AnalysisSummary
from analysis.pipeline.results import assessment_to_json
from webapp.recordings.models import AnalysisRun
from webapp.recordings.words import SKELETON_LABELS, body_part, key_pose_name

# (array, key, what people read: "your movement", "the reference adjusted to your level", ...)
SKELETONS = tuple(
    (f"{key}_positions", key, SKELETON_LABELS[key])
    for key in ("patient", "patient_adjusted", "tutor", "tutor_adjusted")
)
MAX_CHART_POINTS = 600  # long series are downsampled for display


def load_arrays(run: AnalysisRun) -> dict[str, np.ndarray]:
    with run.arrays.open("rb") as handle, np.load(handle, allow_pickle=False) as data:
        return {key: data[key] for key in data.files}


def skeleton_keys(arrays: dict[str, np.ndarray]) -> list[tuple[str, str, str]]:
    patient = arrays["patient_positions"]
    return [s for s in SKELETONS if s[0] in arrays and arrays[s[0]].shape == patient.shape]


def positions_bytes(arrays: dict[str, np.ndarray]) -> bytes:
    """(S, F, J, 3) little-endian float32, skeletons in `skeleton_keys` order."""
    stacked = np.stack([arrays[key] for key, _, _ in skeleton_keys(arrays)])
    return np.ascontiguousarray(stacked, dtype="<f4").tobytes()


def tutor_joint_names(run: AnalysisRun) -> list[str]:
    """ROOT/JOINT names of the exercise's tutor, in file order (the playback skeleton's order)."""
    exercise = run.recording.exercise
    if exercise is None or not exercise.tutor_file or not exercise.tutor_ready():
        return []
    try:
        return list(exercise.tutor_motion().skeleton.names)
    except (OSError, EOFError, ValueError):  # unreadable or missing: no names (BVHError too)
        return []


def joint_names(run: AnalysisRun, arrays: dict[str, np.ndarray], n_joints: int) -> list[str]:
    if "joint_names" in arrays and len(arrays["joint_names"]) == n_joints:
        return [str(name) for name in arrays["joint_names"]]
    names = tutor_joint_names(run)  # older runs stored no names: the tutor's skeleton has them
    return names if len(names) == n_joints else [f"joint {j}" for j in range(n_joints)]


def joint_angles(positions: np.ndarray, parents: np.ndarray, joint: int) -> np.ndarray | None:
    """Angle (degrees) at `joint` between its parent bone and its first child bone, per frame."""
    children = np.flatnonzero(parents == joint)
    parent = int(parents[joint])
    if parent < 0 or children.size == 0:
        return None
    return segment_angles(positions, [(parent, joint, int(children[0]))])[:, 0]


def chart_joints(names: list[str], parents: np.ndarray, result: AnalysisSummary) -> list[int]:
    wanted = set(result.range_of_motion) | set(result.gamma)
    chosen = [j for j, name in enumerate(names) if name in wanted]
    if not chosen:  # no names to match: the joints with both a parent and a child
        chosen = [j for j in range(len(parents)) if parents[j] >= 0 and (parents == j).any()][:4]
    return chosen[:8]


def angle_series(
    arrays: dict[str, np.ndarray], names: list[str], result: AnalysisSummary
) -> dict[str, Any]:
    parents = arrays["parents"].astype(int)
    n_frames = arrays["patient_positions"].shape[0]
    step = max(1, int(np.ceil(n_frames / MAX_CHART_POINTS)))
    frames = np.arange(0, n_frames, step)
    present = {skeleton: key for key, skeleton, _ in skeleton_keys(arrays)}
    # The patient against the tutor synchronised to them (the plain tutor when that is missing).
    shown = ["patient", *[s for s in ("tutor_adjusted", "tutor") if s in present][:1]]
    series = []
    for skeleton in shown:
        key = present[skeleton]
        for joint in chart_joints(names, parents, result):
            values = joint_angles(arrays[key][frames].astype(np.float64), parents, joint)
            if values is not None:
                series.append(
                    {
                        "joint": names[joint],
                        "label": body_part(names[joint]),
                        "skeleton": skeleton,
                        "skeleton_label": SKELETON_LABELS[skeleton],
                        "values": np.round(values, 2).tolist(),
                    }
                )
    return {"frames": frames.tolist(), "series": series}


def type_names(run: AnalysisRun) -> dict[str, str]:
    exercise = run.recording.exercise
    names = getattr(exercise, "landmark_type_names", None) or {}
    return {str(k): str(v) for k, v in names.items()}


def description(run: AnalysisRun, arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    result = run.result or AnalysisSummary.from_json({})
    patient = arrays["patient_positions"]
    names = joint_names(run, arrays, patient.shape[1])
    kinds = type_names(run)
    landmarks = [
        {"frame": int(f), "type": int(t), "name": key_pose_name(int(t), kinds)}
        for f, t in zip(
            arrays.get("landmark_frames", []), arrays.get("landmark_types", []), strict=False
        )
    ]
    return {
        "run": str(run.pk),
        "frames": int(patient.shape[0]),
        "joints": int(patient.shape[1]),
        "fps": float(result.fps or run.recording.fps or 30.0),
        "names": names,
        "labels": [body_part(name) for name in names],
        "parents": [int(p) for p in arrays["parents"]],
        "skeletons": [{"key": k, "label": label} for _, k, label in skeleton_keys(arrays)],
        "layout": "float32 little-endian [skeleton][frame][joint][xyz]",
        "landmarks": landmarks,
        "repetitions": [rep.to_json() for rep in result.repetitions],
        "feedback": [comment.to_dict() for comment in result.feedback],
        "assessment": [assessment_to_json(item) for item in result.assessment],
        "score": result.score if run.result else None,
        "angles": angle_series(arrays, names, result),
    }
