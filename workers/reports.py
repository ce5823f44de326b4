"""Rendering a PDF report into storage (the web app asks for it, a worker makes it)."""

from __future__ import annotations

from datetime import date

from django.core.files.base import ContentFile
from django.core.files.storage import default_storage

from webapp.patients.models import Patient
from webapp.recordings.models import Recording
from webapp.reports import content, pdf


def generate(kind: str, object_id: str, since: str | None, until: str | None) -> bytes:
    """The PDF of one recording (`kind` "recording") or of a patient's progress over a period."""
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


def make_report(
    kind: str, object_id: str, name: str, since: str | None = None, until: str | None = None
) -> str:
    """Store the report under `name` unless it is there already (idempotent); returns `name`."""
    if not default_storage.exists(name):
        stored = default_storage.save(name, ContentFile(generate(kind, object_id, since, until)))
        if stored != name:  # a concurrent twin saved first; keep one copy
            default_storage.delete(stored)
    return name
