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
