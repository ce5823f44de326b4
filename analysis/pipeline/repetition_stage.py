"""Synchronisation with the tutor (004 Alg 11–12) and the alignment of each repetition with its
synchronised tutor repetition (`analysis.pipeline.gestures`)."""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.adjustment.sync import synchronise_landmarks, tutor_frame_map
from analysis.landmarks import Segments
from analysis.pipeline.gestures import GuidanceRules, align_gesture, gesture_score, guidance
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


def synchronise(landmarks: tuple[KeyPose, ...], model: FittedModel) -> Synchronised:
    """Pair the recording's key poses with the tutor's (Alg 11) and map time (Alg 12)."""
    frames = [m.frame for m in landmarks]
    types = [m.type for m in landmarks]
    tutor_frames, tutor_types = model.landmark_frames, model.landmark_types
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


def gesture_results(
    prepared: Prepared,
    segments: Segments,
    progress: FloatArray,
    sync: Synchronised,
    model: FittedModel,
) -> list[GestureResult]:
    """WOOE-DTW of every repetition with its tutor repetition, and what it gives."""
    papers = model.components.papers
    index = list(papers.joint_index)
    reps = model.components.tutor_reps
    step = model.components.scoring_step  # about 30 frames a second: plenty for a shape
    out = []
    for k, (start, end) in enumerate(zip(segments.starts, segments.ends, strict=True)):
        a, b = reps[tutor_repetition(int(start), k, sync, model)]
        tutor_q = papers.tutor_q[a : b + 1 : step]
        patient_q = prepared.local_q[start : end + 1 : step][:, index]
        aligned = align_gesture(tutor_q, patient_q, papers.joint_weights)
        tutor_progress = papers.tutor_progress[a : b + 1 : step]
        tutor_reach = float(tutor_progress.max() - tutor_progress[0])
        own = progress[start : end + 1 : step] - progress[start]
        found = guidance(aligned, own, tutor_reach, RULES)
        last = int(end)
        shifted = tuple(
            Guidance(
                g.type,
                (int(start) + step * g.frames[0], min(last, int(start) + step * g.frames[1])),
            )
            for g in found
        )
        out.append(GestureResult(
            guidance=shifted, score=gesture_score(aligned.mean_cost, papers.gesture_scale),
            alignment_tau=aligned.alignment_tau, similarity=aligned.similarity_deg,
        ))  # fmt: skip
    return out
