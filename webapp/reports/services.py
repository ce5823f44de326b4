"""Where reports are stored and how their generation is requested (after the commit).

A report's storage name includes what it depends on (the run, or the runs of the period), so a
new analysis makes a new report and a stored one is never stale.
"""

from __future__ import annotations

import hashlib

from django.core.files.storage import default_storage
from django.db import transaction
from django.utils import timezone

from webapp.patients.progress import patient_progress
from webapp.recordings.reading import reading_of
from workers.tasks import make_report


def recording_report_name(recording) -> str:
    run = recording.latest_succeeded_run()
    notes = ",".join(str(pk) for pk in recording.notes.values_list("pk", flat=True))
    reading = reading_of(run)  # a therapist's correction rebuilds it: a new report
    notes += f"|{reading.built_at.isoformat()}" if reading else ""
    # A new clinical note makes a new report, as a new run does.
    suffix = f"-{hashlib.sha256(notes.encode()).hexdigest()[:12]}" if notes else ""
    return f"reports/recording-{recording.pk}-{run.pk if run else 'none'}{suffix}.pdf"


def progress_report_name(patient, since, until) -> str:
    runs = ",".join(p["run"] for p in patient_progress(patient, since=since, until=until))
    # A goal set (it lists the goals) or a day passing (a goal's date) makes a new report too.
    goals = ",".join(str(pk) for pk in patient.goals.values_list("pk", flat=True))
    if goals:
        runs += f"|{goals}|{timezone.localdate()}"
    digest = hashlib.sha256(runs.encode()).hexdigest()[:16]
    return f"reports/progress-{patient.pk}-{since or 'start'}-{until or 'now'}-{digest}.pdf"


def request_report(kind: str, object_id: str, name: str, since=None, until=None) -> bool:
    """Enqueue the report unless it is stored; True when it is ready now."""
    if default_storage.exists(name):
        return True
    args = [kind, str(object_id), name, since and since.isoformat(), until and until.isoformat()]
    transaction.on_commit(lambda: make_report.delay(*args))
    return default_storage.exists(name)  # eager Celery outside a transaction: already made
