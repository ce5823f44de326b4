"""Analysing one recording against an exercise model: runs the stages in the order of
`analysis.pipeline.stage_order.ORDER` (the one list of that order; the timer refuses another).

``analyse(motion, model, history=None, on_progress=None)`` is a pure function of its inputs. It
returns a frozen `AnalysisResult` whose ``to_json()`` holds the fields of ``analyse --json``
(CONTRACTS.md) and more, and whose ``arrays()`` holds the per-frame data for playback. Progress is
reported as ``on_progress(stage, fraction)``. Bad input raises a subclass of
`analysis.errors.AnalysisInputError` with a message a therapist can read.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion
from analysis.bvh.plausibility import DEFAULT_LIMITS, Limits
from analysis.clinical import angle_ranges, measure
from analysis.feedback import Comment
from analysis.feedback.advice import Advice
from analysis.pipeline.advice_stage import plain_errors_fail
from analysis.pipeline.clinical_stage import repetition_angles, workspace_summaries
from analysis.pipeline.gestures import Pace
from analysis.pipeline.keyposes import KeyPoseRepetitions, key_pose_repetitions, periodic_analysis
from analysis.pipeline.match import MatchContext, check_fit
from analysis.pipeline.model import FittedModel
from analysis.pipeline.prepare import Prepared, mirrored, prepare, progress_signal
from analysis.pipeline.repetition_stage import gesture_results, synchronise
from analysis.pipeline.results import AnalysisSummary, ExerciseMatch, KeyPose, RepetitionResult
from analysis.pipeline.stage_order import ORDER, Stage, StageOrder
from analysis.pipeline.stages import (
    assess_landmarks,
    feedback_items,
    joint_ranges,
    label_landmarks,
    performance_level,
    playback_arrays,
    repetition_results,
    tempo_median,
)
from analysis.pipeline.still_advice import still_advice

Progress = Callable[[str, float], None]
FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class AnalysisResult:
    """Everything the therapist gets for one recording (see ``to_json`` for the fields)."""

    summary: AnalysisSummary
    playback: dict[str, npt.NDArray[Any]] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict with the CONTRACTS.md fields (frames, fps, landmarks, repetitions,
        score, assessment, feedback, timings_ms) plus metrics, gamma and range_of_motion."""
        return self.summary.to_json()

    def arrays(self) -> dict[str, npt.NDArray[Any]]:
        """Per-frame arrays for playback and charts (float32 where large)."""
        return dict(self.playback)


class StageTimer:
    """Times each stage (ms) and reports progress before it starts; the stages' order, words and
    fractions are `stage_order.ORDER`'s (a stage out of that order raises `StageOrderError`)."""

    def __init__(self, on_progress: Progress | None, order: tuple[Stage, ...] = ORDER) -> None:
        self.on_progress = on_progress
        self.order = StageOrder(order)
        self.timings: dict[str, float] = {}

    @contextmanager
    def __call__(self, key: str) -> Iterator[None]:
        stage = self.order.enter(key)
        if self.on_progress is not None:
            self.on_progress(stage.label, self.order.fraction(key))
        start = time.perf_counter()
        yield
        self.timings[key] = round((time.perf_counter() - start) * 1000.0, 3)


# (timing key, what the progress bar says), read from the one list of the stages
STAGES = tuple((stage.key, stage.label) for stage in ORDER)


def analyse(
    motion: Motion,
    model: FittedModel,
    history: Mapping[str, float] | None = None,
    on_progress: Progress | None = None,
    limits: Limits = DEFAULT_LIMITS,
    *,
    match: MatchContext | None = None,
    own_pace: Pace | None = None,
) -> AnalysisResult:
    """Analyse one recording (see the module docstring); ``limits``: what a recording may be
    (`analysis.bvh.plausibility`, checked before anything is mapped or resampled); ``match``:
    the exercise's name and the clinic's other exercises, for a recording that does not fit
    (`analysis.pipeline.match`: then no repetition and no score); ``own_pace``: the patient's
    usual tempo and reach from an earlier session (`repetition_stage.session_pace`), which
    paper 001's guidance judges this one against as well as against the tutor."""
    timer = StageTimer(on_progress)
    parts = model.components
    papers = parts.papers
    with timer("prepare"):
        prepared = prepare(motion, model.tutor.skeleton, model.fps, parts.axis.rep_frames, limits)
        progress, used_mirror = progress_signal(prepared, parts.axis, parts.mirror)
    with timer("landmark_identification"):
        identified = papers.landmarks.identify(prepared.motion)
    with timer("landmark_refining"):
        refined = papers.landmarks.refine_identified(identified, prepared.motion)
    with timer("periodic_analysis"):
        kept, origin, periodic = periodic_analysis(papers.landmarks, refined)
    with timer("repetitions"):
        cut = key_pose_repetitions(kept, origin, papers.landmarks, progress, parts.axis.rep_frames)
        landmarks = _shown_landmarks(cut, prepared, model)
    with timer("match"):
        points = mirrored(prepared.points, parts.mirror) if used_mirror else prepared.points
        found = int(cut.segments.starts.size)
        fit = check_fit(prepared.motion, points, progress, found, model, match)
    if not fit.fits:
        return _unfit(prepared, model, (fit, cut, used_mirror), timer, on_progress)
    with timer("synchronisation"):
        sync = synchronise(landmarks, model)
    with timer("alignment"):
        # scored as the tutor's side when the patient used the other one
        scored = prepared
        if used_mirror:
            scored = replace(prepared, points=mirrored(prepared.points, parts.mirror))
        gestures = gesture_results(prepared, cut.segments, progress, sync, model, own_pace)
    with timer("assessment"):  # before the scores (see stage_order)
        assessment = assess_landmarks(prepared, landmarks, model)
    with timer("scores"):
        repetitions = repetition_results(
            scored, cut.segments, progress, model, gestures, assessment
        )
    with timer("performance_level"):
        gamma = performance_level(assessment, history)
    with timer("adjustment"):
        playback = playback_arrays(prepared, landmarks, model, gamma)
    with timer("clinical_angles"):  # only what the recording measures; notes say why not
        measured = measure(prepared.motion)
        series, angles = measured.series, angle_ranges(measured.series)
        repetitions = repetition_angles(series, repetitions)
        # a plain error (a main angle far short, a trunk lean held) fails its repetition
        repetitions = plain_errors_fail(repetitions, model, used_mirror, prepared.motion)
    with timer("feedback"):  # after the angles (see stage_order)
        advice, feedback = feedback_items(
            repetitions, assessment, model, used_mirror, prepared.motion
        )
    with timer("workspace"):
        workspace = workspace_summaries(prepared.motion, model.involved_joints)
    if on_progress is not None:
        on_progress("done", 1.0)
    summary = AnalysisSummary(
        frames=prepared.n_frames,
        fps=round(prepared.motion.fps, 6),
        landmarks=landmarks,
        repetitions=repetitions,
        score=_recording_score(repetitions),
        assessment=assessment,
        feedback=feedback,
        advice=advice,
        gamma=gamma,
        mirrored=used_mirror,
        range_of_motion=joint_ranges(prepared, model),
        tempo=tempo_median(repetitions),
        timings_ms=timer.timings,
        segmentation=cut.segmentation,
        periodic=periodic,
        pass_threshold=papers.threshold.value,
        clinical_angles=angles,
        clinical_notes=measured.notes,
        workspace=workspace,
    )
    return AnalysisResult(summary, playback)


def _unfit(
    prepared: Prepared,
    model: FittedModel,
    found: tuple[ExerciseMatch, KeyPoseRepetitions, bool],
    timer: StageTimer,
    on_progress: Progress | None,
) -> AnalysisResult:
    """A recording that does not show the exercise: no repetition, no score, no level; its
    joint angles, reach and playback (the tutor at its own pace) are still measured."""
    fit, cut, used_mirror = found
    with timer("adjustment"):
        playback = playback_arrays(prepared, (), model, {})
    with timer("clinical_angles"):
        measured = measure(prepared.motion)
        angles = angle_ranges(measured.series)
    with timer("feedback"):  # the exercise's own parts left (nearly) still: say which
        advice = still_advice(measured.series, model) if fit.looks_like is None else Advice()
    with timer("workspace"):
        workspace = workspace_summaries(prepared.motion, model.involved_joints)
    if on_progress is not None:
        on_progress("done", 1.0)
    summary = AnalysisSummary(
        frames=prepared.n_frames, fps=round(prepared.motion.fps, 6), landmarks=(),
        repetitions=(), score=None, mirrored=used_mirror, advice=advice,
        feedback=tuple(Comment(c.frame, c.text) for c in advice.corrections),
        range_of_motion=joint_ranges(prepared, model), timings_ms=timer.timings,
        segmentation=cut.segmentation, pass_threshold=model.components.papers.threshold.value,
        clinical_angles=angles, clinical_notes=measured.notes, workspace=workspace, match=fit,
    )  # fmt: skip
    return AnalysisResult(summary, playback)


def _shown_landmarks(
    cut: KeyPoseRepetitions, prepared: Prepared, model: FittedModel
) -> tuple[KeyPose, ...]:
    """The key poses the result shows; on the fallback cut, labelled from the progress axis."""
    if cut.segmentation == "fallback":
        return label_landmarks(prepared, cut.segments, model)
    return cut.landmarks


def _recording_score(repetitions: tuple[RepetitionResult, ...]) -> float:
    """The mean repetition score (0 when no repetition was found)."""
    if not repetitions:
        return 0.0
    return round(float(np.mean([r.score for r in repetitions])), 2)
