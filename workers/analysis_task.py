"""Analysing one recording: claim the run, call the pipeline, store summary and arrays."""

from __future__ import annotations

import dataclasses
import io
import logging
import os
import socket
import time
import traceback
from collections.abc import Mapping
from typing import Any

import numpy as np
from django.conf import settings
from django.core.files.base import ContentFile
from django.db import InterfaceError, OperationalError, transaction

from analysis import __version__ as code_version
from analysis.bvh import AnalysisInputError, Limits, check_recording
from analysis.pipeline import AnalysisResult, analyse
from analysis.pipeline.gestures import Pace
from analysis.sources import read_recording
from analysis.sources.video import SUFFIXES as VIDEO_SUFFIXES
from webapp.patients.models import PerformanceLevel
from webapp.recordings.models import AnalysisRun
from webapp.recordings.pace import usual_pace
from webapp.recordings.storage import read_verified
from workers import exercise_models, runs
from workers.exercise_match import match_context
from workers.limits import LIMIT_ERRORS, limit_reason

log = logging.getLogger(__name__)
# A video's frames go through the pose estimator first: the bar's first half (percent).
VIDEO_READ_SHARE = 50
GENERIC_FAILURE = (
    "The analysis failed unexpectedly. The team has the details; please try again later."
)
# Errors that say nothing about the recording: the database or the disk was briefly away.
TRANSIENT_ERRORS: tuple[type[BaseException], ...] = (OperationalError, InterfaceError, OSError)


class TransientAnalysisError(Exception):
    """The run could not go on for a passing reason; the task retries with the same lease."""

    def __init__(self, run_id: str, token: str | None, cause: BaseException) -> None:
        super().__init__(f"analysis {run_id} interrupted: {cause!r}")
        self.token = token


def worker_name() -> str:
    """The machine and process analysing the run (which process to look at, or stop)."""
    return f"{socket.gethostname()} pid {os.getpid()}"


def analyse_run(run_id: str, resume_token: str | None = None) -> str:
    """Run one analysis to its end. Returns the final status, or 'skipped' if not ours.

    A transient error (database or storage briefly unavailable) raises TransientAnalysisError
    carrying the lease token, so the retried task resumes this claim rather than waiting for the
    lease to expire.
    """
    token = None
    try:
        token = runs.claim(run_id, worker_name(), resume_token)
        if token is None:
            return "skipped"
        return analyse_claimed(run_id, token)
    except TRANSIENT_ERRORS as error:
        log.warning("analysis %s interrupted, will retry: %r", run_id, error)
        raise TransientAnalysisError(run_id, token or resume_token, error) from error


def analyse_claimed(run_id: str, token: str) -> str:
    run = AnalysisRun.objects.select_related("recording__exercise", "recording__patient").get(
        pk=run_id
    )
    try:
        result, model_row = compute(run, token)
    except TRANSIENT_ERRORS:
        raise
    except LIMIT_ERRORS as error:  # past this server's memory or time for one analysis
        runs.fail(run_id, token, limit_reason(error), f"{error!r}\n{traceback.format_exc()}")
        return "failed"
    except AnalysisInputError as error:
        runs.fail(run_id, token, str(error), traceback.format_exc())
        return "failed"
    except Exception as error:  # the run must end with a reason whatever went wrong
        log.exception("analysis %s failed", run_id)
        runs.fail(run_id, token, GENERIC_FAILURE, f"{error!r}\n{traceback.format_exc()}")
        return "failed"
    store(run, token, result, model_row)
    return "succeeded"


def compute(run: AnalysisRun, token: str) -> tuple[AnalysisResult, Any]:
    recording = run.recording
    if recording.exercise is None:
        raise AnalysisInputError("Choose the exercise of this recording before analysing it.")
    runs.report(str(run.pk), token, "loading", 2)
    # Any capture source, by the stored file's real suffix (analysis.sources); a video's frames
    # take the pose estimator a while, so reading it moves the bar to half way.
    start, span = (
        (VIDEO_READ_SHARE, 95 - VIDEO_READ_SHARE)
        if recording.file.name.lower().endswith(VIDEO_SUFFIXES)
        else (5, 90)
    )

    def on_reading(fraction: float) -> None:
        runs.report(str(run.pk), token, "loading", 2 + int((start - 2) * fraction))

    imported = read_recording(recording.file.name, read_verified(recording), progress=on_reading)
    motion = imported.motion
    # Refused here, with its plain reason, before a model is built or anything allocated for it
    # (the model's frame rate and joints are its tutor's).
    limits = Limits.from_settings(settings)
    tutor = recording.exercise.tutor_motion()
    check_recording(motion, tutor.fps, len(tutor.skeleton.names), limits)
    # A worker may build: the first analysis of an exercise fits its model from the tutor (the
    # web app only ever loads one, `exercise_models.load_active`).
    model_row, model = exercise_models.load_or_build(recording.exercise)
    history = previous_levels(recording)

    def on_progress(stage: str, fraction: float) -> None:
        runs.report(str(run.pk), token, stage, start + int(span * fraction))
        stage_delay()

    match = match_context(recording.exercise, imported.source.kind)
    result = analyse(
        motion, model, history=history, on_progress=on_progress, limits=limits,
        match=match, own_pace=earlier_pace(recording), lost_frames=imported.lost_frames,
    )  # fmt: skip
    summary = dataclasses.replace(result.summary, source=imported.source)
    return dataclasses.replace(result, summary=summary), model_row


def stage_delay() -> None:
    """Fault-injection hook: the SIGKILL test slows every stage so it can kill mid-analysis.

    ``ANALYSIS_STAGE_DELAY_SECONDS`` is 0 (no delay) unless a test sets it in the worker's
    environment; real recordings analyse in well under a second, too fast to interrupt.
    """
    delay = float(getattr(settings, "ANALYSIS_STAGE_DELAY_SECONDS", 0.0))
    if delay > 0:
        time.sleep(delay)


def previous_levels(recording) -> dict[str, float]:
    levels = PerformanceLevel.objects.filter(
        patient=recording.patient, exercise=recording.exercise
    ).values_list("joint", "gamma")
    return dict(levels)


def earlier_pace(recording) -> Pace | None:
    """The patient's usual pace before this recording (`webapp.recordings.pace`)."""
    return usual_pace(recording.patient_id, recording.exercise_id, recording.uploaded_at)


def npz_bytes(arrays: dict[str, np.ndarray]) -> bytes:
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)  # type: ignore[arg-type]  # numpy stub: **kwds vs allow_pickle
    return buffer.getvalue()


def store(run: AnalysisRun, token: str, result: AnalysisResult, model_row) -> None:
    """Write the arrays file, then the result in one transaction; no file outlives a failure."""
    name = f"{run.pk}.npz"
    stored = run.arrays.storage.save(f"runs/{name}", ContentFile(npz_bytes(result.arrays())))
    finished = False
    try:
        with transaction.atomic():
            # Ends the run, then refreshes the patient's stored dashboard rows (attention list,
            # progress point) from it, as `runs.fail` does for a failure.
            finished = runs.succeed(
                str(run.pk),
                token,
                summary=result.to_json(),
                score=result.summary.score,
                arrays=stored,
                model=model_row,
                code_version=code_version,
            )
            if finished:
                save_levels(run, result.summary.gamma)
    finally:
        if not finished:
            run.arrays.storage.delete(stored)


def save_levels(run: AnalysisRun, gamma: Mapping[str, float]) -> None:
    recording = run.recording
    for joint, value in gamma.items():
        PerformanceLevel.objects.update_or_create(
            patient=recording.patient,
            exercise=recording.exercise,
            joint=joint,
            defaults={"gamma": float(value)},
        )
