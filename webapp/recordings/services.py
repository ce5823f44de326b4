"""The web app's only door to the task queue: tasks are enqueued after the commit."""

from __future__ import annotations

import logging

from django.db import transaction
from kombu.exceptions import OperationalError as BrokerUnavailable

from webapp.recordings.models import AnalysisRun, RecognitionState, Recording
from workers.tasks import analyse_recording, recognise_exercise

log = logging.getLogger(__name__)


def start_analysis(recording: Recording) -> AnalysisRun:
    """Create a QUEUED run and enqueue its analysis once the transaction commits."""
    run = AnalysisRun.objects.create(recording=recording)
    run_id = str(run.pk)
    transaction.on_commit(lambda: enqueue_analysis(run_id))
    return run


def analyse_now(run: AnalysisRun) -> AnalysisRun:
    """Analyse a QUEUED run in this process, without waiting for a worker (the demo loader, so a
    fresh clinic shows results before any worker runs); a message already enqueued for the run
    then finds it taken and does nothing. Returns the finished run."""
    analyse_recording.apply(args=[str(run.pk)])
    run.refresh_from_db()
    return run


def enqueue_analysis(run_id: str) -> None:
    """Hand the run to the broker; if it is down, the upload still stands (already committed):
    the run stays QUEUED and the beat task `requeue_lost_runs` enqueues it later."""
    try:
        analyse_recording.delay(run_id)
    except (BrokerUnavailable, OSError):
        log.warning("broker unavailable; run %s waits for the requeue task", run_id, exc_info=True)


def confirm_exercise(recording: Recording, exercise) -> AnalysisRun | None:
    """Set the exercise of a recording uploaded without one and start its analysis, once."""
    with transaction.atomic():
        updated = Recording.objects.filter(pk=recording.pk, exercise__isnull=True).update(
            exercise=exercise
        )
        if updated != 1:
            return None
        recording.exercise = exercise
        return start_analysis(recording)


def start_recognition(recording: Recording) -> None:
    """Ask a worker which exercise a recording uploaded without one shows, once the transaction
    commits (nothing is analysed until someone confirms). A recognition already queued or
    running is not asked twice."""
    asked = Recording.objects.filter(pk=recording.pk, exercise__isnull=True).exclude(
        recognition__in=[RecognitionState.QUEUED, RecognitionState.RUNNING]
    )
    if asked.update(recognition=RecognitionState.QUEUED, recognition_progress=0) != 1:
        return
    recording.recognition, recording.recognition_progress = RecognitionState.QUEUED, 0
    recording_id = str(recording.pk)
    transaction.on_commit(lambda: enqueue_recognition(recording_id))


def enqueue_recognition(recording_id: str) -> None:
    """Hand the recognition to the broker (the analyses queue); if it is down, the recording page
    says the exercise could not be recognised and offers the choice at once."""
    try:
        recognise_exercise.delay(recording_id)
    except (BrokerUnavailable, OSError):
        log.warning(
            "broker unavailable; recording %s is not recognised", recording_id, exc_info=True
        )
        Recording.objects.filter(pk=recording_id, recognition=RecognitionState.QUEUED).update(
            recognition=RecognitionState.FAILED
        )
