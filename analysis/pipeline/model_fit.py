"""Fitting the parts of an exercise model from the tutor (and labelled recordings).

Kept apart from `analysis.pipeline.model` (the container and its file format) so that each fitted
part is
one small function: involved joints, progress axis, repetition templates, score calibration.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.assessment import (
    LandmarkAssessor,
    RepetitionScorer,
    ThresholdAssessor,
    fit_scorer,
    joint_relevance,
    landmark_features,
    repetition_features,
    tutor_mean_poses,
)
from analysis.bvh import AnalysisInputError, Motion
from analysis.kinematics import flatten, relative_to_start, resample, rotations, scaled_positions
from analysis.landmarks import KeyPoses, ProgressAxis, fit_axis
from analysis.pipeline.model_parts import PaperParts, fit_paper_parts
from analysis.pipeline.prepare import mirrored, prepare, progress_signal

FloatArray = npt.NDArray[np.float64]
SCORING_FPS = 30.0
Progress = Callable[[str, float], None]


class TutorKeyPosesError(AnalysisInputError):
    """The exercise's reference recording lacks the key poses a model needs (none marked yet,
    or marked so that no whole repetition is known): no recording of it can be analysed until
    they are marked, so trying again before that cannot help."""

    def __init__(self, problem: str) -> None:
        super().__init__(
            f"The exercise cannot analyse recordings yet: {problem}. Mark the key poses on the "
            "reference recording of the exercise (at least two where a repetition starts, around "
            "one whole repetition); trying again before that cannot help."
        )


@dataclass(frozen=True, eq=False)
class ModelComponents:
    """The fitted parts of an exercise model that the pipeline's stages read.

    ``axis``: the tutor's progress axis (repetition boundaries); ``mirror``: each joint's
    left/right counterpart; ``involved_index`` / ``scored_index``: joints assessed / scored;
    ``templates``: the tutor's repetitions relative to their start, (n_k, D) each, scored at every
    ``scoring_step``-th frame by ``scorer``; ``tutor_reps``: their (start, end) frames;
    ``mean_poses``: the tutor's mean local rotations per key-pose type, (J, 4) each;
    ``assessor``: the per-joint level model; ``papers``: the key-pose model, joint weights,
    GB-DTW scale and pass threshold (`analysis.pipeline.model_parts`).
    """

    axis: ProgressAxis
    mirror: list[int]
    involved_index: list[int]
    scored_index: list[int]
    templates: list[FloatArray]
    scorer: RepetitionScorer
    scoring_step: int
    tutor_reps: list[tuple[int, int]]
    mean_poses: dict[int, FloatArray]
    assessor: LandmarkAssessor | ThresholdAssessor
    papers: PaperParts


@dataclass(frozen=True)
class AssessmentParts:
    """The tutor's mean pose per key-pose type and the per-joint assessor fitted on them."""

    mean_poses: dict[int, FloatArray]
    assessor: LandmarkAssessor | ThresholdAssessor


@dataclass(frozen=True, eq=False)
class TrainingRecording:
    """A therapist-labelled recording: key poses and a label ('correct', 'incorrect' or 1..4)."""

    motion: Motion
    key_poses: KeyPoses  # frames of the file as given
    label: str


def mirror_permutation(names: Sequence[str]) -> list[int]:
    """For each joint, the index of its left/right counterpart (itself when it has none)."""
    index = {n: k for k, n in enumerate(names)}
    out = []
    for name in names:
        swapped = name.replace("Left", "\0").replace("Right", "Left").replace("\0", "Right")
        out.append(index.get(swapped, index[name]))
    return out


def moving_joints(
    tutor: Motion, frames: Sequence[int], types: Sequence[int], min_deg: float = 15.0
) -> list[str]:
    """Joints whose rotation differs by at least ``min_deg`` between the tutor's key-pose types
    (at least the three that differ most), in file order; the root is never one of them."""
    relevance = joint_relevance(tutor_mean_poses(rotations(tutor), frames, types))
    relevance[0] = 0.0
    keep = relevance >= min(min_deg, float(np.sort(relevance)[-3]))
    return [n for n, k in zip(tutor.skeleton.names, keep, strict=True) if k]


def tutor_repetitions(frames: Sequence[int], types: Sequence[int]) -> list[tuple[int, int]]:
    """(start, end) of each tutor repetition: a type-1 landmark to the frame before the next."""
    starts = [f for f, t in zip(frames, types, strict=True) if t == 1]
    return [(a, max(b - 1, a)) for a, b in itertools.pairwise(starts)]


def templates(features: FloatArray, reps: list[tuple[int, int]]) -> list[FloatArray]:
    """Each tutor repetition's movement relative to its starting pose: list of (n_k, D)."""
    return [relative_to_start(features[a : b + 1]) for a, b in reps]


def _end_of_range(frames: Sequence[int], types: Sequence[int]) -> npt.NDArray[np.int64]:
    return np.array([f for f, t in zip(frames, types, strict=True) if t != 1], dtype=np.int64)


def fit_components(  # noqa: PLR0917 (mirrors build_model's arguments)
    tutor: Motion,
    frames: list[int],
    types: list[int],
    joints: Sequence[str] | None,
    training: Sequence[Any],
    on_progress: Progress | None,
) -> tuple[ModelComponents, list[str], dict[str, Any]]:
    """Fit every part; returns (components, involved joint names, training report)."""
    report = on_progress or (lambda stage, fraction: None)
    names = tutor.skeleton.names
    all_points = scaled_positions(tutor, list(range(len(names))))
    involved = list(joints) if joints else moving_joints(tutor, frames, types)
    unknown = sorted(set(involved) - set(names))
    if unknown:
        raise ValueError(f"the tutor has no joint named {', '.join(unknown)}")
    report("features", 0.2)
    reps = tutor_repetitions(frames, types)
    if not reps:
        raise TutorKeyPosesError("only one of its key poses marks where a repetition starts")
    starts = np.array([a for a, _ in reps], dtype=np.int64)
    axis = fit_axis(flatten(all_points), starts, _end_of_range(frames, types))
    involved_idx = [names.index(n) for n in involved]
    # Scores look at every joint but the root (the origin): compensations show in joints that
    # the exercise does not move.
    scored = list(range(1, len(names)))
    tutor_templates = templates(flatten(all_points[:, scored]), reps)
    report("calibration", 0.5)
    # Scores compare shapes of movement: 30 frames a second are plenty, and DTW costs n × m.
    step = max(1, round(tutor.fps / SCORING_FPS))
    coarse = [t[::step] for t in tutor_templates]
    mirror = mirror_permutation(names)
    labelled = training_deviations(training, coarse, scored, step, tutor, (axis, mirror))
    scorer = fit_scorer(coarse, labelled)
    parts = assessment_parts(tutor, frames, types, training)
    report("key poses", 0.6)
    papers = fit_paper_parts(
        tutor, frames, types, involved_idx, axis.progress(flatten(all_points)), reps,
        _at_tutor_rate(training, tutor),
        [(scorer.raw_score(f), ok) for f, ok in labelled],
    )  # fmt: skip
    scorer = replace(scorer, raw_pass=papers.threshold.raw)  # its boundary onto the one scale
    components = ModelComponents(
        axis=axis,
        mirror=mirror,
        involved_index=involved_idx,
        scored_index=scored,
        templates=tutor_templates,
        scorer=scorer,
        scoring_step=step,
        tutor_reps=reps,
        mean_poses=parts.mean_poses,
        assessor=parts.assessor,
        papers=papers,
    )
    report("done", 1.0)
    summary = {
        "tutor_repetitions": len(reps),
        "labelled_repetitions": len(labelled),
        "involved_joints": list(involved),  # the joints the joint weights belong to, in order
    }
    return components, involved, {**summary, "scorer": scorer.as_dict(), **papers.report()}


def _at_tutor_rate(
    training: Sequence[TrainingRecording], tutor: Motion
) -> list[tuple[Motion, list[int], list[int]]]:
    """Labelled recordings resampled to the tutor's frame rate, their key-pose frames moved."""
    out = []
    for item in training:
        motion = resample(item.motion, tutor.fps)
        rate = motion.fps / item.motion.fps
        last = motion.n_frames - 1
        marks = sorted({min(round(f * rate), last): t for f, t in item.key_poses}.items())
        out.append((motion, [f for f, _ in marks], [t for _, t in marks]))
    return out


def assessment_parts(
    tutor: Motion, frames: list[int], types: list[int], training: Sequence[TrainingRecording]
) -> AssessmentParts:
    """Tutor mean poses per landmark type and the per-joint assessor: trained on recordings
    labelled with a level (1..4, applied to each of their landmarks) when there are some, else
    the threshold fallback calibrated on the tutor's own variability."""
    tutor_q = rotations(tutor)
    means = tutor_mean_poses(tutor_q, frames, types)
    assessor: Any = ThresholdAssessor().fit(landmark_features(tutor_q, frames, types, means), types)
    leveled = [t for t in training if t.label in ("1", "2", "3", "4")]
    if leveled:
        feats, levels, kinds = [], [], []
        for item in leveled:
            known = [(f, k) for f, k in item.key_poses if k in means]
            q = rotations(item.motion)
            feats.append(landmark_features(q, [f for f, _ in known], [k for _, k in known], means))
            levels.append(np.full(feats[-1].shape[:2], int(item.label)))
            kinds += [k for _, k in known]
        assessor = LandmarkAssessor().fit(np.concatenate(feats), np.concatenate(levels), kinds)
    return AssessmentParts(means, assessor)


def training_deviations(  # noqa: PLR0917 (the scoring set-up the pipeline uses)
    training: Sequence[TrainingRecording],
    tutor_templates: list[FloatArray],
    scored: list[int],
    step: int,
    tutor: Motion,
    side: tuple[ProgressAxis, list[int]],
) -> list[tuple[FloatArray, bool]]:
    """(repetition features, is correct) for every repetition of the labelled recordings, prepared
    as the pipeline prepares a recording: at the tutor's frame rate, and mirrored when the patient
    did a one-sided exercise with the other side (as the pipeline scores them)."""
    axis, mirror = side
    out: list[tuple[FloatArray, bool]] = []
    for item in training:
        prepared = prepare(item.motion, tutor.skeleton, tutor.fps, axis.rep_frames)
        _, use_mirror = progress_signal(prepared, axis, mirror)
        points = mirrored(prepared.points, mirror) if use_mirror else prepared.points
        feats = flatten(points[:, scored])
        correct = item.label in ("correct", "1")
        rate = prepared.motion.fps / item.motion.fps  # landmarks are frames of the file as given
        marks = item.key_poses
        for first, last in tutor_repetitions(marks.frames.tolist(), marks.types.tolist()):
            a, b = round(first * rate), round(last * rate)
            segment = relative_to_start(feats[a : b + 1])[::step]
            out.append((repetition_features(segment, tutor_templates), correct))
    return out


__all__ = [
    "ModelComponents",
    "RepetitionScorer",
    "TrainingRecording",
    "fit_components",
    "mirror_permutation",
]
