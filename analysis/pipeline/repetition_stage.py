"""Synchronisation with the tutor (004 Alg 11–12) and the alignment of each repetition with its
synchronised tutor repetition (`analysis.pipeline.gestures`)."""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from analysis.adjustment.sync import synchronise_landmarks, tutor_frame_map
from analysis.landmarks import Segments
from analysis.pipeline.gestures import (
    GuidanceRules,
    Pace,
    align_gesture,
    gesture_score,
    guidance,
    repetition_pace,
    usual_pace,
)
from analysis.pipeline.model import FittedModel
from analysis.pipeline.prepare import Prepared
from analysis.pipeline.results import Guidance, KeyPose

FloatArray = npt.NDArray[np.float64]
RULES = GuidanceRules()


@dataclass(frozen=True, eq=False)
class Synchronised:
    """Alg 11's landmark pairs as {patient frame: tutor frame}, and Alg 12's fractional tutor
    frame for every patient frame (None when patient and tutor share no key-pose type)."""

    partners: dict[int, int]
    frame_map: FloatArray | None


@dataclass(frozen=True)
class GestureResult:
    """The alignment stage's figures for one repetition (frames absolute in the recording)."""

    guidance: tuple[Guidance, ...]
    score: float
    alignment_tau: float
    similarity: float
    excursion: float  # `Pace.reach`: the involved joints' excursion over the tutor's


def synchronise(landmarks: tuple[KeyPose, ...], model: FittedModel) -> Synchronised:
    """Pair the recording's key poses with the tutor's (Alg 11) and map time (Alg 12)."""
    frames = [m.frame for m in landmarks]
    types = [m.type for m in landmarks]
    tutor_frames, tutor_types = model.key_poses.frames, model.key_poses.types
    pairs = synchronise_landmarks(types, tutor_types)
    if not pairs or not frames:
        return Synchronised({}, None)
    frame_map = tutor_frame_map(
        pairs, frames, tutor_frames, frames[-1] + 1, tutor_types=tutor_types
    )
    return Synchronised({frames[u]: tutor_frames[t] for u, t in pairs}, frame_map)


def tutor_repetition(start: int, k: int, sync: Synchronised, model: FittedModel) -> int:
    """Index of the tutor repetition a patient repetition starting at ``start`` is compared
    with: the one whose start pose Alg 11 paired with it, else the k-th (cyclically)."""
    reps = model.components.tutor_reps
    partner = sync.partners.get(start)
    starts = [a for a, _ in reps]
    if partner is not None:
        index = bisect.bisect_right(starts, partner) - 1
        if index >= 0:
            return index
    return k % len(reps)


def pace_reference(model: FittedModel) -> tuple[list[int], list[int], FloatArray, float]:
    """The involved joints, their mirror images' joints, the tutor's excursion of both
    (`reference_excursion`) and the tutor's repetition length (median, model frames), as
    computed when the model was built (`analysis.pipeline.tutor_parts.PaceReference`)."""
    pace = model.tutor_parts.pace
    return pace.index, pace.mirror, pace.excursion, pace.tutor_frames


def session_pace(
    prepared: Prepared, spans: Sequence[tuple[int, int]], model: FittedModel
) -> Pace | None:
    """The patient's usual pace in a session: the median `Pace` of its repetitions (first,
    last frame), to judge a later session's tempo and reach against (``own``)."""
    step = model.components.scoring_step
    index, mirror, reference, tutor_frames = pace_reference(model)
    paces = []
    for start, end in spans:
        patient = prepared.local_q[start : end + 1 : step]
        tempo = (end - start + 1) / tutor_frames
        paces.append(repetition_pace(patient[:, index], patient[:, mirror], reference, tempo)[0])
    usual = usual_pace(paces)
    return None if usual is None else replace(usual, earlier=True)


def gesture_results(  # noqa: PLR0917 (the stage's inputs, as run.py holds them)
    prepared: Prepared,
    segments: Segments,
    progress: FloatArray,
    sync: Synchronised,
    model: FittedModel,
    own: Pace | None = None,
) -> list[GestureResult]:
    """WOOE-DTW of every repetition with its tutor repetition, and what it gives; ``own``: the
    patient's usual pace from earlier sessions (None: this session's repetitions so far)."""
    papers, parts = model.components.papers, model.components
    reps, step = parts.tutor_reps, parts.scoring_step  # about 30 frames a second
    index, mirror, reference, tutor_frames = pace_reference(model)
    out, paces = [], []
    for k, (start, end) in enumerate(zip(segments.starts, segments.ends, strict=True)):
        a, b = reps[tutor_repetition(int(start), k, sync, model)]
        patient = prepared.local_q[start : end + 1 : step]
        aligned = align_gesture(papers.tutor_q[a : b + 1 : step], patient[:, index],
                                papers.joint_weights)  # fmt: skip
        tempo = (end - start + 1) / tutor_frames
        pace, series = repetition_pace(patient[:, index], patient[:, mirror], reference, tempo)
        paces.append(pace)
        found = guidance(aligned, series, pace, own or usual_pace(paces), RULES)
        shifted = tuple(
            Guidance(g.type, (int(start) + step * g.frames[0],
                              min(int(end), int(start) + step * g.frames[1])))
            for g in found
        )  # fmt: skip
        out.append(GestureResult(
            guidance=shifted, score=gesture_score(aligned.mean_cost, papers.gesture_scale),
            alignment_tau=aligned.alignment_tau, similarity=aligned.similarity_deg,
            excursion=round(pace.reach, 3),
        ))  # fmt: skip
    return out
