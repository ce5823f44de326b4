"""The web app's only door to the task queue: tasks are enqueued after the commit."""

from __future__ import annotations

from django.db import transaction

from webapp.recordings.models import AnalysisRun, Recording


def start_analysis(recording: Recording) -> AnalysisRun:
    """Create a QUEUED run and enqueue its analysis once the transaction commits."""
    from workers.tasks import analyse_recording

    run = AnalysisRun.objects.create(recording=recording)
    run_id = str(run.pk)
    transaction.on_commit(lambda: analyse_recording.delay(run_id))
    return run


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
