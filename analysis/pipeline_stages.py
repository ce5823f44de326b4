"""The stages of `analysis.pipeline` after preparation: landmarks, repetition scores, per-joint
assessment, feedback, performance level and playback arrays. Each takes and returns plain data."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis import quaternions as quat
from analysis.feedback import Grammar, LandmarkAssessment
from analysis.guidance import guidance_for
from analysis.model import ExerciseModel
from analysis.pipeline_levels import gamma_update, joint_levels, tutor_mean_pose
from analysis.pipeline_prepare import Prepared
from analysis.posefeatures import flatten, range_of_motion, relative_to_start
from analysis.scoring import repetition_distance
from analysis.segmentation import Segments

FloatArray = npt.NDArray[np.float64]


def label_landmarks(prepared: Prepared, segments: Segments, model: ExerciseModel) -> list[dict]:
    """Type 1 at each repetition start (and the last end); at each end of range, the tutor's
    non-start landmark type whose mean pose is closest."""
    peak_types = sorted({t for t in model.landmark_types if t != 1}) or [2]
    marks: list[dict] = []
    for start, peak in zip(segments.starts, segments.peaks, strict=True):
        marks.append({"frame": int(start), "type": 1})
        marks.append({"frame": int(peak), "type": _closest_type(prepared, int(peak), peak_types, model)})
    if segments.ends.size:
        marks.append({"frame": int(segments.ends[-1]), "type": 1})
    return marks


def _closest_type(prepared: Prepared, frame: int, types: list[int], model: ExerciseModel) -> int:
    if len(types) == 1:
        return types[0]
    pose = prepared.local_q[frame]
    costs = [quat.angle_between(tutor_mean_pose(model, t), pose).sum() for t in types]
    return types[int(np.argmin(costs))]


def repetition_results(
    prepared: Prepared, segments: Segments, progress: FloatArray, model: ExerciseModel
) -> list[dict[str, Any]]:
    """Per repetition: frames, score 0–100, distance to the tutor, guidance, tempo."""
    parts = model.components
    movement = flatten(prepared.points[:, parts["involved_index"]])
    tutor_frames = float(np.median([len(t) for t in parts["templates"]]))
    out = []
    for start, end, peak in zip(segments.starts, segments.ends, segments.peaks, strict=True):
        segment = relative_to_start(movement[start : end + 1])
        distance = repetition_distance(segment, parts["templates"])
        reach = float(progress[peak] - progress[start])
        tempo = (end - start + 1) / tutor_frames
        out.append({
            "start": int(start), "end": int(end), "peak": int(peak),
            "score": round(parts["score_scale"].score(distance), 2),
            "distance": round(distance, 5), "reach": round(reach, 3),
            "tempo": round(float(tempo), 3), "guidance": guidance_for(tempo, reach),
        })  # fmt: skip
    return out


def assess_landmarks(
    prepared: Prepared, landmarks: list[dict], model: ExerciseModel
) -> list[dict[str, Any]]:
    """Per landmark, a level 1 (as the tutor) … 4 for every involved joint."""
    names = model.joint_names
    involved = model.components["involved_index"]
    out = []
    for mark in landmarks:
        levels = joint_levels(prepared.local_q[mark["frame"]], tutor_mean_pose(model, mark["type"]))
        out.append({
            "frame": mark["frame"], "type": mark["type"],
            "levels": {names[j]: int(levels[j]) for j in involved},
        })  # fmt: skip
    return out


def feedback_items(
    assessment: list[dict[str, Any]], model: ExerciseModel, history: Mapping[str, float] | None
) -> tuple[list[dict[str, Any]], dict[str, float]]:
    """Feedback sentences from the exercise's grammar, and the updated performance level γ."""
    grammar = Grammar.parse(model.grammar)
    assessed = [LandmarkAssessment.from_dict(a) for a in assessment]
    comments = [c.to_dict() for c in grammar.comments(assessed)]
    return comments, gamma_update(history, assessment, list(model.involved_joints))


def playback_arrays(
    prepared: Prepared, landmarks: list[dict], model: ExerciseModel, gamma: Mapping[str, float]
) -> dict[str, npt.NDArray[Any]]:
    """Per-frame world positions (float32) for the viewer and the charts."""
    from analysis.kinematics import positions

    patient = positions(prepared.motion)[:, prepared.joint_index]
    return {
        "patient_positions": patient.astype(np.float32),
        "parents": model.tutor.skeleton.parents.astype(np.int32),
        "landmark_frames": np.array([m["frame"] for m in landmarks], dtype=np.int32),
        "landmark_types": np.array([m["type"] for m in landmarks], dtype=np.int32),
    }


def summary_metrics(
    prepared: Prepared, repetitions: list[dict[str, Any]], model: ExerciseModel
) -> dict[str, Any]:
    """Range of motion per involved joint and tempo against the tutor."""
    tempos = [r["tempo"] for r in repetitions]
    return {
        "range_of_motion": range_of_motion(prepared.angles, list(model.involved_joints)),
        "tempo": round(float(np.median(tempos)), 3) if tempos else None,
        "repetition_count": len(repetitions),
    }
