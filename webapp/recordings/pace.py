"""The patient's usual pace for an exercise: the median tempo and excursion of the repetitions of
their latest earlier session of it. Paper 001's guidance judges a session against it as well as
against the reference (`analysis.pipeline.gestures.pace_guidance`), so the worker's analysis of an
upload and a live session of the same patient read it from here alike: a patient hears live what
the saved session's page later says."""

from __future__ import annotations

import datetime

import numpy as np

from analysis.pipeline.gestures import Pace
from webapp.recordings.models import AnalysisRun, RunStatus


def usual_pace(patient_id: int, exercise_id: int, before: datetime.datetime) -> Pace | None:
    """The pace of the patient's latest session of the exercise uploaded before ``before``; None
    for a first session, one that did not fit its exercise, or one analysed before the excursion
    was stored."""
    earlier = (
        AnalysisRun.objects.filter(
            recording__patient_id=patient_id, recording__exercise_id=exercise_id,
            recording__uploaded_at__lt=before, status=RunStatus.SUCCEEDED,
            recording__deleted_at__isnull=True,
        )
        .order_by("-recording__uploaded_at", "-created_at")
        .first()
    )  # fmt: skip
    summary = earlier.result if earlier is not None else None
    if summary is None or not summary.match.fits:
        return None
    paces = [(r.tempo, r.excursion) for r in summary.repetitions if r.excursion is not None]
    if not paces:
        return None
    tempo, excursion = np.median(np.asarray(paces), axis=0)
    return Pace(float(tempo), float(excursion), earlier=True)
