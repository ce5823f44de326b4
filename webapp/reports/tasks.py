"""The report task, registered with the `workers` Celery app."""

from __future__ import annotations

from datetime import date

from django.core.files.base import ContentFile
from django.core.files.storage import default_storage

from workers.celery import app


def generate(kind: str, object_id: str, since: str | None, until: str | None) -> bytes:
    from webapp.patients.models import Patient
    from webapp.recordings.models import Recording
    from webapp.reports import content, pdf

    if kind == "recording":
        recording = Recording.objects.select_related("patient", "exercise", "clinic").get(
            pk=object_id
        )
        return pdf.recording_pdf(content.recording_content(recording))
    patient = Patient.objects.select_related("clinic").get(pk=object_id)
    period = (
        date.fromisoformat(since) if since else None,
        date.fromisoformat(until) if until else None,
    )
    return pdf.progress_pdf(content.progress_content(patient, *period))


@app.task(name="webapp.reports.tasks.make_report", autoretry_for=(OSError,), max_retries=3)
def make_report(
    kind: str, object_id: str, name: str, since: str | None = None, until: str | None = None
) -> str:
    """Render one PDF report into storage under `name` (idempotent: kept if already there)."""
    if not default_storage.exists(name):
        stored = default_storage.save(name, ContentFile(generate(kind, object_id, since, until)))
        if stored != name:  # a concurrent twin saved first; keep one copy
            default_storage.delete(stored)
    return name
