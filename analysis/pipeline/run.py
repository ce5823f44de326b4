"""Analysing one recording against an exercise model: runs the stages in the order of
`analysis.pipeline.stage_order.ORDER` (the one list of that order; the timer refuses another).

``analyse(motion, model, history=None, on_progress=None)`` is a pure function of its inputs. It
returns a frozen `AnalysisResult` whose ``to_json()`` holds the fields of ``analyse --json``
(the interface contract) and more, and whose ``arrays()`` holds the per-frame data for playback.
Progress is
reported as ``on_progress(stage, fraction)``. Bad input raises a subclass of
`analysis.bvh.errors.AnalysisInputError` with a message a therapist can read.

It runs in four phases, each returning a frozen result: `find_repetitions` (`Found`: stages
prepare … match), `score` (`Scored`: synchronisation … performance_level, only for a recording
that shows the exercise), `measure_recording` (`Measures`: adjustment, clinical_angles) and
`explain` (`Explained`: feedback, workspace). The recording's forward kinematics and body parts
are computed once, in preparation, and handed along in `Prepared`; what depends on the model
alone (the parsed grammar, the tutor's clinical reference, playback take and pace reference)
was computed when the model was built (`analysis.pipeline.tutor_parts`).
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
from analysis.clinical import Measured, angle_ranges, measure
from analysis.dtw.cost_blas import single_threaded_blas
from analysis.feedback import Comment, LandmarkAssessment
from analysis.feedback.advice import Advice
from analysis.pipeline.advice_stage import judge_repetitions
from analysis.pipeline.clinical_stage import (
    lost_at_rate,
    repetition_angles,
    workspace_summaries,
)
from analysis.pipeline.curves import angle_curves
from analysis.pipeline.gestures import Pace
from analysis.pipeline.judgement import Judgement
from analysis.pipeline.keyposes import KeyPoseRepetitions, key_pose_repetitions, periodic_analysis
from analysis.pipeline.match import MatchContext, check_fit
from analysis.pipeline.model import FittedModel
from analysis.pipeline.prepare import Prepared, mirrored, prepare, progress_signal
from analysis.pipeline.repetition_stage import gesture_results, synchronise
from analysis.pipeline.results import (
    AnalysisSummary,
    AngleRange,
    ExerciseMatch,
    KeyPose,
    PeriodicSummary,
    RepetitionResult,
    WorkspaceSummary,
)
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
from analysis.pipeline.tutor_parts import compensations

Progress = Callable[[str, float], None]
FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class AnalysisResult:
    """Everything the therapist gets for one recording (see ``to_json`` for the fields)."""

    summary: AnalysisSummary
    playback: dict[str, npt.NDArray[Any]] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict with the interface contract's fields (frames, fps, landmarks,
        repetitions,
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


@dataclass(frozen=True, eq=False)
class Found:
    """Phase 1, finding the repetitions (stages prepare … match): the recording as prepared,
    its progress signal, whether it was done with the other side, the key poses and
    repetitions found, the key poses shown, and whether it shows the exercise at all."""

    prepared: Prepared
    progress: FloatArray
    used_mirror: bool
    cut: KeyPoseRepetitions
    periodic: PeriodicSummary
    landmarks: tuple[KeyPose, ...]
    fit: ExerciseMatch


@dataclass(frozen=True, eq=False)
class Scored:
    """Phase 2, scoring (synchronisation … performance_level): the per-joint assessment of
    every key pose, the repetitions with their scores, and the performance level γ."""

    assessment: tuple[LandmarkAssessment, ...] = ()
    repetitions: tuple[RepetitionResult, ...] = ()
    gamma: dict[str, float] = field(default_factory=dict)
    own_pace: Pace | None = None  # the patient's usual pace from an earlier session


@dataclass(frozen=True, eq=False)
class Measures:
    """Phase 3, measuring (adjustment, clinical_angles): the playback arrays, the clinical
    angles (series and ranges, and why an angle is missing), the compensations, and the
    repetitions with their angle ranges, each judged once (`analysis.pipeline.judgement`)."""

    playback: dict[str, npt.NDArray[Any]]
    measured: Measured
    angles: dict[str, AngleRange]
    compensations: dict[str, FloatArray]
    repetitions: tuple[RepetitionResult, ...]
    judged: tuple[Judgement, ...] = ()


@dataclass(frozen=True, eq=False)
class Explained:
    """Phase 4, explaining (feedback, workspace): the advice, the feedback list and the reach
    of each hand."""

    advice: Advice
    feedback: tuple[Comment, ...]
    workspace: dict[str, WorkspaceSummary]


def analyse(
    motion: Motion,
    model: FittedModel,
    history: Mapping[str, float] | None = None,
    on_progress: Progress | None = None,
    limits: Limits = DEFAULT_LIMITS,
    *,
    match: MatchContext | None = None,
    own_pace: Pace | None = None,
    lost_frames: Mapping[str, npt.NDArray[np.bool_]] | None = None,
) -> AnalysisResult:
    """Analyse one recording (see the module docstring); ``limits``: what a recording may be
    (`analysis.bvh.plausibility`, checked before anything is mapped or resampled); ``match``:
    the exercise's name and the clinic's other exercises, for a recording that does not fit
    (`analysis.pipeline.match`: then no repetition and no score); ``own_pace``: the patient's
    usual tempo and reach from an earlier session (`repetition_stage.session_pace`), which
    paper 001's guidance judges this one against as well as against the tutor; ``lost_frames``:
    per joint the capture lost in some of ``motion``'s frames (``"left_shoulder"``: (F,) bool,
    `analysis.sources.ImportedRecording.lost_frames`), frames left out of that joint's clinical
    angles (the count and scores read the motion as it is)."""
    timer = StageTimer(on_progress)
    # BLAS on one thread for the whole analysis: the DTW's cost blocks ask for that limit
    # hundreds of times a recording, and once it is held each ask only counts
    with single_threaded_blas():
        found = find_repetitions(motion, model, limits, match, timer)
        scored = score(found, model, (history, own_pace), timer) if found.fit.fits else Scored()
        lost = lost_at_rate(lost_frames or {}, motion.frame_time, found.prepared.motion)
        measures = measure_recording(found, scored, model, timer, lost)
        explained = explain(found, measures, scored, model, timer)
    if on_progress is not None:
        on_progress("done", 1.0)
    summary = _summary(found, scored, (measures, explained), model, timer)
    return AnalysisResult(summary, {**measures.playback, **angle_curves(measures.measured)})


def find_repetitions(
    motion: Motion,
    model: FittedModel,
    limits: Limits,
    match: MatchContext | None,
    timer: StageTimer,
) -> Found:
    """Phase 1: prepare the recording, find its key poses and repetitions, check it fits."""
    parts = model.components
    papers = parts.papers
    with timer("prepare"):
        prepared = prepare(motion, model.tutor.skeleton, model.fps, parts.axis.rep_frames, limits)
        progress, used_mirror = progress_signal(prepared, parts.axis, parts.mirror)
    with timer("landmark_identification"):
        identified = papers.landmarks.identify(prepared.motion, prepared.kinematics)
    with timer("landmark_refining"):
        refined = papers.landmarks.refine_identified(
            identified, prepared.motion, prepared.kinematics
        )
    with timer("periodic_analysis"):
        kept, origin, periodic = periodic_analysis(papers.landmarks, refined)
    with timer("repetitions"):
        cut = key_pose_repetitions(kept, origin, papers.landmarks, progress, parts.axis.rep_frames)
        landmarks = _shown_landmarks(cut, prepared, model)
    with timer("match"):
        points = mirrored(prepared.points, parts.mirror) if used_mirror else prepared.points
        found = int(cut.segments.starts.size)
        seen = (prepared.motion, prepared.kinematics)
        fit = check_fit(seen, points, progress, found, model, match)
    return Found(prepared, progress, used_mirror, cut, periodic, landmarks, fit)


def score(
    found: Found,
    model: FittedModel,
    before: tuple[Mapping[str, float] | None, Pace | None],
    timer: StageTimer,
) -> Scored:
    """Phase 2 (a recording that fits only): align each repetition with the tutor, assess
    every key pose, score the repetitions and update the performance level; ``before``: the
    patient's levels and own pace from earlier sessions."""
    history, own_pace = before
    prepared, segments = found.prepared, found.cut.segments
    with timer("synchronisation"):
        sync = synchronise(found.landmarks, model)
    with timer("alignment"):
        # scored as the tutor's side when the patient used the other one
        scored = prepared
        if found.used_mirror:
            scored = replace(prepared, points=mirrored(prepared.points, model.components.mirror))
        gestures = gesture_results(prepared, segments, found.progress, sync, model, own_pace)
    with timer("assessment"):  # before the scores (see stage_order)
        assessment = assess_landmarks(prepared, found.landmarks, model)
    with timer("scores"):
        repetitions = repetition_results(
            scored, segments, found.progress, model, gestures, assessment
        )
    with timer("performance_level"):
        gamma = performance_level(assessment, history)
    return Scored(assessment, repetitions, gamma, own_pace)


def measure_recording(
    found: Found,
    scored: Scored,
    model: FittedModel,
    timer: StageTimer,
    lost: Mapping[str, npt.NDArray[np.bool_]] | None = None,
) -> Measures:
    """Phase 3: the playback skeletons (the tutor at its own pace for a recording that does
    not fit), the clinical angles and compensations, each repetition's angle ranges; ``lost``:
    the frames (at the model's rate) left out of a lost joint's angles."""
    prepared = found.prepared
    with timer("adjustment"):
        shown = found.landmarks if found.fit.fits else ()
        playback = playback_arrays(prepared, shown, model, scored.gamma)
    with timer("clinical_angles"):  # only what the recording measures; notes say why not
        kin, body = prepared.kinematics, prepared.body
        measured = measure(prepared.motion, kin=kin, body=body, lost=lost)
        angles = angle_ranges(measured.series)
        series = compensations(kin.positions, body) if found.fit.fits else {}
        repetitions = repetition_angles(measured.series, scored.repetitions)
        # one judgement per repetition: its verdict (a plain error fails it), guidance, reasons
        repetitions, judged = judge_repetitions(
            repetitions, model, found.used_mirror, series, scored.own_pace
        )
    return Measures(playback, measured, angles, series, repetitions, judged)


def explain(
    found: Found, measures: Measures, scored: Scored, model: FittedModel, timer: StageTimer
) -> Explained:
    """Phase 4: the feedback in plain words (for a recording that does not fit, which of the
    exercise's own parts were left still) and the reach of each hand."""
    prepared = found.prepared
    with timer("feedback"):  # after the angles (see stage_order)
        if found.fit.fits:
            advice, feedback = feedback_items(
                measures.repetitions, scored.assessment, model, found.used_mirror,
                measures.compensations, measures.judged,
            )  # fmt: skip
        else:  # the exercise's own parts left (nearly) still: say which
            still = found.fit.looks_like is None
            advice = still_advice(measures.measured.series, model) if still else Advice()
            feedback = tuple(Comment(c.frame, c.text) for c in advice.corrections)
    with timer("workspace"):
        seen = (prepared.kinematics, prepared.body)
        workspace = workspace_summaries(prepared.motion, model.involved_joints, seen)
    return Explained(advice, feedback, workspace)


def _summary(
    found: Found,
    scored: Scored,
    told: tuple[Measures, Explained],
    model: FittedModel,
    timer: StageTimer,
) -> AnalysisSummary:
    """The stored summary of the four phases (no repetition, score or level when unfit)."""
    measures, explained = told
    prepared, fits = found.prepared, found.fit.fits
    repetitions = measures.repetitions
    return AnalysisSummary(
        frames=prepared.n_frames, fps=round(prepared.motion.fps, 6),
        landmarks=found.landmarks if fits else (), repetitions=repetitions,
        score=_recording_score(repetitions) if fits else None,
        assessment=scored.assessment, feedback=explained.feedback, advice=explained.advice,
        gamma=scored.gamma, mirrored=found.used_mirror,
        range_of_motion=joint_ranges(prepared, model),
        tempo=tempo_median(repetitions) if fits else None, timings_ms=timer.timings,
        segmentation=found.cut.segmentation, periodic=found.periodic if fits else PeriodicSummary(),
        pass_threshold=model.components.papers.threshold.value,
        clinical_angles=measures.angles, clinical_notes=measures.measured.notes,
        workspace=explained.workspace, match=found.fit,
    )  # fmt: skip


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
