"""Playback payload of one analysis run: a small JSON description and raw float32 positions.

The worker stores per-frame world positions in the run's ``.npz``; the browser receives them as
little-endian float32 laid out ``[skeleton][frame][joint][xyz]`` so it never parses BVH.
Skeletons the run does not have (older runs, or before the lead adds them) are left out.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from analysis.clinical.labels import angle_label, involved_regions, region_of
from analysis.clinical.norms import norm_for
from analysis.kinematics.forward_kinematics import segment_angles
from analysis.pipeline import AnalysisSummary
from analysis.pipeline.curves import curve_name
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


def chart_frames(n_frames: int, curves: list[np.ndarray]) -> np.ndarray:
    """At most about MAX_CHART_POINTS frames, evenly spread, plus each curve's smallest and
    largest value's frame: the chart reaches the same extremes as the table of ranges."""
    step = max(1, int(np.ceil(n_frames / MAX_CHART_POINTS)))
    kept = set(range(0, n_frames, step))
    for values in curves:
        if np.isfinite(values).any():
            kept |= {int(np.nanargmin(values)), int(np.nanargmax(values))}
    return np.array(sorted(kept), dtype=int)


def _degrees(values: np.ndarray) -> list[float | None]:
    return [round(float(v), 2) if np.isfinite(v) else None for v in values]


def clinical_series(arrays: dict[str, np.ndarray], involved: list[str]) -> dict[str, Any]:
    """The clinical angles frame by frame (`analysis.pipeline.curves`: the series the table's
    ranges come from), named in words with their normal adult range; those of the regions the
    exercise moves are shown at first. Runs analysed before the curves were kept have none."""
    curves = {name: arrays[key] for key in arrays if (name := curve_name(key))}
    frames = chart_frames(arrays["patient_positions"].shape[0], list(curves.values()))
    regions = involved_regions(involved)
    series = []
    for name, values in curves.items():
        try:
            norm: tuple[float, float] | None = (norm_for(name).minimum, norm_for(name).maximum)
        except KeyError:
            norm = None
        series.append(
            {
                "angle": name,
                "label": angle_label(name),
                "normal": norm,
                "involved": region_of(name) in regions,
                "values": _degrees(values[frames].astype(np.float64)),
            }
        )
    return {"frames": frames.tolist(), "series": series}


def segment_series(
    arrays: dict[str, np.ndarray], names: list[str], result: AnalysisSummary
) -> dict[str, Any]:
    """The angle between each charted body segment and the next (180° is straight), for the
    therapists who ask for it; not a clinical angle, and never shown as one."""
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


def involved_joints(run: AnalysisRun, result: AnalysisSummary) -> list[str]:
    """The exercise's involved joints; else the joints the analysis compared."""
    exercise = run.recording.exercise
    return list(getattr(exercise, "involved_joints", None) or result.range_of_motion)


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
        "angles": clinical_series(arrays, involved_joints(run, result)),
        "segments": segment_series(arrays, names, result),
    }
