"""Recognising the exercise of a recording uploaded without one (paper 002 retrieval), in a worker.

The upload answered at once; this stores the suggestion on the recording and its progress for
the recording page, and never analyses: the uploader confirms the exercise first. Candidates are
the patient's prescribed exercises (the clinic's, when none is prescribed).
"""

from __future__ import annotations

import logging

from django.db.models import QuerySet

from analysis.bvh import AnalysisInputError
from analysis.sources import read_recording
from webapp.recordings.models import RecognitionState, Recording
from webapp.recordings.prescribed import recognition_candidates
from webapp.recordings.similar import identify_exercise
from webapp.recordings.storage import DamagedRecordingError, read_verified

log = logging.getLogger(__name__)
# Progress (%) when the file is read; reading the candidates' features fills the rest up to 95.
READ_PROGRESS = 10
FEATURES_PROGRESS = 95
PROGRESS_STEP = 5
# What makes a recording unrecognisable rather than the worker broken: its rig, its file.
UNRECOGNISABLE = (AnalysisInputError, ValueError, DamagedRecordingError)


def waiting(recording_id: str) -> QuerySet[Recording]:
    """The recording while it still waits for its exercise and its recognition is asked."""
    return Recording.objects.filter(
        pk=recording_id,
        exercise__isnull=True,
        recognition__in=[RecognitionState.QUEUED, RecognitionState.RUNNING],
    )


def report(recording_id: str, percent: float) -> None:
    waiting(recording_id).update(recognition_progress=int(percent))


def recognise(recording_id: str) -> str:
    """Recognise one recording's exercise; returns the recognition's final state ('skipped' when
    nothing was asked: already confirmed, or already recognised by a redelivered message)."""
    if waiting(recording_id).update(recognition=RecognitionState.RUNNING) != 1:
        return "skipped"
    recording = Recording.objects.select_related("patient").get(pk=recording_id)
    try:
        guess = best_guess(recording)
    except UNRECOGNISABLE:
        log.info("could not recognise the exercise of %s", recording_id, exc_info=True)
        guess = None
    except Exception:
        finish(recording_id, None)  # the page then offers the choice instead of waiting forever
        raise
    return finish(recording_id, guess)


def best_guess(recording: Recording):
    """The nearest candidate exercise with its distance, or None when there is no candidate."""
    motion = read_recording(recording.file.name, read_verified(recording)).motion
    report(str(recording.pk), READ_PROGRESS)
    span = FEATURES_PROGRESS - READ_PROGRESS
    shown = [READ_PROGRESS]

    def progress(fraction: float) -> None:
        percent = int(READ_PROGRESS + span * fraction)
        if percent - shown[0] >= PROGRESS_STEP:  # hundreds of examples: not one write each
            report(str(recording.pk), percent)
            shown[0] = percent

    return identify_exercise(motion, recognition_candidates(recording.patient), progress)


def finish(recording_id: str, guess) -> str:
    """Store the suggestion (or that there is none) and mark the recognition ended."""
    if guess is None:
        state = RecognitionState.FAILED
        changes = {"suggested_exercise": None, "suggestion_distance": None}
    else:
        state = RecognitionState.DONE
        changes = {"suggested_exercise": guess.exercise, "suggestion_distance": guess.distance}
    waiting(recording_id).update(recognition=state, recognition_progress=100, **changes)
    return str(state)
