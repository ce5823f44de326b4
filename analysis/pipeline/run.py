"""Analysing one recording against an exercise model: the only place the stage order lives.

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
from analysis.landmarks import segment
from analysis.pipeline.model import FittedModel
from analysis.pipeline.prepare import mirrored, prepare, progress_signal
from analysis.pipeline.results import AnalysisSummary, RepetitionResult
from analysis.pipeline.stages import (
    assess_landmarks,
    feedback_items,
    joint_ranges,
    label_landmarks,
    playback_arrays,
    repetition_results,
    tempo_median,
)

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
    """Times each stage (ms) and reports progress before it starts."""

    def __init__(self, on_progress: Progress | None, stages: list[str]) -> None:
        self.on_progress = on_progress
        self.stages = stages
        self.timings: dict[str, float] = {}

    @contextmanager
    def __call__(self, stage: str) -> Iterator[None]:
        if self.on_progress is not None:
            self.on_progress(stage, self.stages.index(stage) / len(self.stages))
        start = time.perf_counter()
        yield
        self.timings[stage] = round((time.perf_counter() - start) * 1000.0, 3)


STAGES = ["prepare", "repetitions", "scores", "assessment", "feedback", "playback"]


def analyse(
    motion: Motion,
    model: FittedModel,
    history: Mapping[str, float] | None = None,
    on_progress: Progress | None = None,
) -> AnalysisResult:
    """Analyse one recording (see the module docstring)."""
    timer = StageTimer(on_progress, STAGES)
    parts = model.components
    with timer("prepare"):
        prepared = prepare(motion, model.joint_names, model.fps, parts.axis.rep_frames)
    with timer("repetitions"):
        progress, used_mirror = progress_signal(prepared, parts.axis, parts.mirror)
        segments = segment(progress, parts.axis.rep_frames)
        landmarks = label_landmarks(prepared, segments, model)
    with timer("scores"):
        # scored as the tutor's side when the patient used the other one
        scored = prepared
        if used_mirror:
            scored = replace(prepared, points=mirrored(prepared.points, parts.mirror))
        repetitions = repetition_results(scored, segments, progress, model)
    with timer("assessment"):
        assessment = assess_landmarks(prepared, landmarks, model)
    with timer("feedback"):
        feedback, gamma = feedback_items(assessment, model, history)
    with timer("playback"):
        playback = playback_arrays(prepared, landmarks, model, gamma)
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
        gamma=gamma,
        mirrored=used_mirror,
        range_of_motion=joint_ranges(prepared, model),
        tempo=tempo_median(repetitions),
        timings_ms=timer.timings,
    )
    return AnalysisResult(summary, playback)


def _recording_score(repetitions: tuple[RepetitionResult, ...]) -> float:
    """The mean repetition score (0 when no repetition was found)."""
    if not repetitions:
        return 0.0
    return round(float(np.mean([r.score for r in repetitions])), 2)
