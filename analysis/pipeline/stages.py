"""The stages of `analysis.pipeline` after preparation: landmarks, repetition scores, per-joint
assessment, feedback, performance level and playback arrays. Each returns the typed results of
`analysis.pipeline.results`."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.adjustment import Performance, demonstration_skeletons, gamma_vector
from analysis.assessment import landmark_features, repetition_features, update_levels
from analysis.assessment.findings import findings, tutor_ranges, tutor_spreads
from analysis.assessment.joints import N_LEVELS
from analysis.assessment.limbs import arm_first
from analysis.assessment.scoring import MISSED_CAP, missed_key_pose, repetition_features_all
from analysis.clinical import angle_ranges, angle_series
from analysis.feedback import Comment, Grammar, LandmarkAssessment
from analysis.feedback.advice import MAX_CORRECTIONS, Advice, advise
from analysis.feedback.text import correction_rules
from analysis.kinematics import flatten, range_of_motion, relative_to_start
from analysis.kinematics import quaternions as quat
from analysis.landmarks import KeyPoses, Segments
from analysis.pipeline.advice_stage import (
    main_part,
    recording_passed,
    repetition_measures,
    tutor_reference,
    unnamed_failures,
)
from analysis.pipeline.judgement import Judgement
from analysis.pipeline.model import FittedModel
from analysis.pipeline.model_fit import ModelComponents
from analysis.pipeline.prepare import Prepared, in_model_order
from analysis.pipeline.repetition_stage import GestureResult
from analysis.pipeline.results import KeyPose, RepetitionResult

FloatArray = npt.NDArray[np.float64]


def label_landmarks(
    prepared: Prepared, segments: Segments, model: FittedModel
) -> tuple[KeyPose, ...]:
    """Type 1 at each repetition start (and the last end); at each end of range, the tutor's
    non-start landmark type whose mean pose is closest."""
    peak_types = sorted({t for t in model.key_poses.types.tolist() if t != 1}) or [2]
    marks: list[KeyPose] = []
    for start, peak in zip(segments.starts, segments.peaks, strict=True):
        marks.append(KeyPose(int(start), 1))
        marks.append(KeyPose(int(peak), _closest_type(prepared, int(peak), peak_types, model)))
    if segments.ends.size:
        marks.append(KeyPose(int(segments.ends[-1]), 1))
    return tuple(marks)


def _closest_type(prepared: Prepared, frame: int, types: list[int], model: FittedModel) -> int:
    if len(types) == 1:
        return types[0]
    pose = prepared.local_q[frame]
    means = model.components.mean_poses
    costs = [quat.angle_between(means[t], pose).sum() if t in means else np.inf for t in types]
    return types[int(np.argmin(costs))]


def scoring_features(
    points: FloatArray,
    start: int,
    end: int,
    parts: ModelComponents,
    templates: Sequence[FloatArray] | None = None,
) -> FloatArray:
    """The features the exercise's scorer scores a repetition by, from frames start..end of the
    recording's (F, J, 3) scaled positions (`scaled_positions`; the tutor's side): the movement
    of the scored joints since the repetition began against the tutor's repetitions. Offline and
    live (`analysis.live.judged`) alike; ``templates``: `scoring_templates` when already made."""
    thinned = scoring_templates(parts) if templates is None else templates
    return repetition_features(scoring_segment(points, start, end, parts), thinned)


def scoring_segment(points: FloatArray, start: int, end: int, parts: ModelComponents) -> FloatArray:
    """Frames start..end of the scored joints' positions, relative to the first, at the scoring
    rate: what `scoring_features` compares with the tutor's repetitions."""
    movement = flatten(np.take(points[start : end + 1], parts.scored_index, axis=1))
    return relative_to_start(movement)[:: parts.scoring_step]


def scoring_templates(parts: ModelComponents) -> list[FloatArray]:
    """The tutor's repetitions at the scoring rate (every ``scoring_step``-th frame), each one
    array in memory order: made once for all of a recording's repetitions, not once for each
    repetition and template, as the DTW would copy the strided views every time."""
    return [np.ascontiguousarray(t[:: parts.scoring_step]) for t in parts.templates]


def repetition_results(  # noqa: PLR0917 (the stage's inputs, as run.py holds them)
    prepared: Prepared,
    segments: Segments,
    progress: FloatArray,
    model: FittedModel,
    gestures: Sequence[GestureResult],
    assessment: Sequence[LandmarkAssessment] = (),
) -> tuple[RepetitionResult, ...]:
    """Per repetition: frames, score 0–100 and pass/fail, distance to the tutor, reach, tempo,
    and the alignment stage's guidance, GB-DTW score and paper 003 figures. A repetition whose
    key pose the per-joint assessment finds clearly missed scores below the pass threshold."""
    parts = model.components
    threshold = parts.papers.threshold.value
    tutor_frames = float(np.median([len(t) for t in parts.templates]))
    # every repetition's features at once: their alignments with the tutor's are one call
    all_features = repetition_features_all(
        [scoring_segment(prepared.points, int(a), int(b), parts)
         for a, b in zip(segments.starts, segments.ends, strict=True)],
        scoring_templates(parts),
    )  # fmt: skip
    out = []
    for k, (start, end, peak) in enumerate(
        zip(segments.starts, segments.ends, segments.peaks, strict=True)
    ):
        features = all_features[k]
        dev = features[: len(parts.scored_index)]
        score = parts.scorer.score(features)
        inside = [a.levels for a in assessment if start < a.frame <= end and a.type != 1]
        reach = float(progress[peak] - progress[start])
        # missed by falling short of it: going past the key pose is an overdone, not a miss
        if reach < 1.0 and missed_key_pose(inside, N_LEVELS):
            score = min(score, MISSED_CAP)
        score = round(score, 2)
        gesture = gestures[k]
        out.append(RepetitionResult(
            start=int(start), end=int(end), peak=int(peak), score=score,
            deviation=round(float(dev.mean()), 5),
            reach=round(reach, 3),
            tempo=round(float((end - start + 1) / tutor_frames), 3),
            guidance=gesture.guidance, passed=bool(score >= threshold),
            gbdtw_score=gesture.score, alignment_tau=gesture.alignment_tau,
            similarity=gesture.similarity, excursion=gesture.excursion,
        ))  # fmt: skip
    return tuple(out)


def assess_landmarks(
    prepared: Prepared, landmarks: tuple[KeyPose, ...], model: FittedModel
) -> tuple[LandmarkAssessment, ...]:
    """Per landmark, a level 1 (as the tutor) … 4 for every involved joint."""
    means = model.components.mean_poses
    marks = [m for m in landmarks if m.type in means]
    if not marks:
        return ()
    frames, types = [m.frame for m in marks], [m.type for m in marks]
    features = landmark_features(prepared.local_q, frames, types, means)
    levels = model.components.assessor.predict(features, types)
    names, involved = model.joint_names, model.components.involved_index
    return tuple(
        LandmarkAssessment(f, t, {names[j]: int(row[j]) for j in involved if row[j] > 0})
        for f, t, row in zip(frames, types, levels, strict=True)
    )


def tutor_angle_ranges(model: FittedModel) -> tuple[dict[str, float], dict[str, float]]:
    """The median range (degrees) of each clinical angle over the tutor's repetitions, and its
    SD over them."""
    series = angle_series(model.tutor)
    per_repetition = [{k: v.range for k, v in angle_ranges(series, a, b).items()}
                      for a, b in model.components.tutor_reps]  # fmt: skip
    return tutor_ranges(per_repetition), tutor_spreads(per_repetition)


def feedback_items(  # noqa: PLR0917 (the stage's inputs, as run.py holds them)
    repetitions: tuple[RepetitionResult, ...],
    assessment: tuple[LandmarkAssessment, ...],
    model: FittedModel,
    mirrored: bool,
    series: Mapping[str, FloatArray] | None = None,
    judged: Sequence[Judgement] = (),
) -> tuple[Advice, tuple[Comment, ...]]:
    """The corrections and what went well (`analysis.feedback.advice`), said by the exercise's
    grammar; and the feedback list: the corrections at the frame where each first happened,
    then, for an older grammar written per key pose, its comments with repeats left out;
    ``series``: the recording's compensations (`analysis.pipeline.tutor_parts.compensations`);
    ``judged``: each repetition's judgement (`advice_stage.judge_repetitions`): a failed
    repetition no correction names gets one of its own (`advice_stage.unnamed_failures`)."""
    grammar = model.rules
    reference = tutor_reference(model)
    measures = repetition_measures(repetitions, series)
    passed = recording_passed(repetitions, model)
    found = arm_first(findings(measures, reference, mirrored, passed=passed))
    if judged:
        found = unnamed_failures(found, judged, [r.start for r in repetitions])
    # the default sentences say what a grammar written before a kind of finding has no rule for
    fallback = Grammar(tuple(correction_rules()))
    advice = advise(grammar, found, len(repetitions), main_part(reference.ranges), fallback)
    comments = [Comment(c.frame, c.text) for c in advice.corrections]
    said = {c.text for c in comments}
    for comment in grammar.comments(list(assessment)) if not grammar.has_findings else ():
        if comment.feedback not in said and len(comments) < MAX_CORRECTIONS:
            comments.append(comment)
            said.add(comment.feedback)
    return advice, tuple(comments)


def performance_level(
    assessment: tuple[LandmarkAssessment, ...], history: Mapping[str, float] | None
) -> dict[str, float]:
    """The patient's performance level γ per joint, updated with this session's levels."""
    per_joint: dict[str, list[int]] = {}
    for item in assessment:
        for joint, level in item.levels.items():
            per_joint.setdefault(joint, []).append(level)
    gamma = update_levels(history, per_joint)
    return {j: round(v, 4) for j, v in gamma.items()}


def playback_arrays(
    prepared: Prepared,
    landmarks: tuple[KeyPose, ...],
    model: FittedModel,
    gamma: Mapping[str, float],
) -> dict[str, npt.NDArray[Any]]:
    """The four demonstration skeletons (paper 004, 7.3) as world positions (F, J, 3) float32 on
    the patient's timeline, with the model's joint names and parents, and the landmarks."""
    skeleton = model.tutor.skeleton
    shown = KeyPoses.of([m.frame for m in landmarks], [m.type for m in landmarks])
    kin, index = prepared.kinematics, prepared.joint_index
    patient = Performance(prepared.local_q, in_model_order(kin.local_t, index), shown)
    demo = demonstration_skeletons(
        skeleton, patient, model.tutor_parts.take, model.components.mean_poses,
        gamma_vector(dict(gamma), skeleton.names), tutor_root="patient",
        patient_world=in_model_order(kin.positions, index),
    )  # fmt: skip
    return {
        "patient_positions": demo.patient.astype(np.float32),
        "patient_adjusted_positions": demo.patient_adjusted.astype(np.float32),
        "tutor_positions": demo.tutor.astype(np.float32),
        "tutor_adjusted_positions": demo.tutor_adjusted.astype(np.float32),
        "tutor_frame_map": demo.tutor_frame_map.astype(np.float32),
        "parents": skeleton.parents.astype(np.int32),
        "joint_names": np.array(skeleton.names),
        "landmark_frames": shown.frames.astype(np.int32),
        "landmark_types": shown.types.astype(np.int32),
    }


def tempo_median(repetitions: tuple[RepetitionResult, ...]) -> float | None:
    """The median tempo of the repetitions against the tutor (None without repetitions)."""
    tempos = [r.tempo for r in repetitions]
    return round(float(np.median(tempos)), 3) if tempos else None


def joint_ranges(prepared: Prepared, model: FittedModel) -> dict[str, float]:
    """Range of motion (degrees) per involved joint."""
    return range_of_motion(prepared.angles, list(model.involved_joints))
