"""Keeping the stored attention list (`PatientAttention`) up to date.

- `refresh_patient`: after a run of the patient succeeds or fails (`workers.runs`), three small
  queries over that one patient's rows, then one write (`refresh_after_run` also stores the
  run's progress point, `webapp.patients.progress_store`);
- `refresh_clinic` / `refresh_all`: beat (`workers.tasks.refresh_attention`), for what changes
  with time alone (a failure older than two weeks, sessions missed), and after a bulk load.

The home page then reads one page of rows (`read_page`): two queries whatever the clinic's size.
"""

from __future__ import annotations

import logging
from typing import Any

from django.core.paginator import Page, Paginator
from django.db import transaction

from webapp.accounts.models import Clinic
from webapp.dashboard.attention import Attention, patients_needing_attention
from webapp.dashboard.models import PatientAttention

log = logging.getLogger(__name__)


def stored(entry: Attention, clinic_id: Any) -> PatientAttention:
    reasons = [
        {
            "kind": reason.kind,
            "text": reason.text,
            "urgency": reason.urgency,
            "recording_id": str(reason.recording_id) if reason.recording_id else None,
        }
        for reason in entry.reasons
    ]
    return PatientAttention(
        patient_id=entry.patient_id, clinic_id=clinic_id, urgency=entry.urgency, reasons=reasons
    )


def save_rows(rows: list[PatientAttention]) -> None:
    PatientAttention.objects.bulk_create(
        rows,
        batch_size=1000,
        update_conflicts=True,
        unique_fields=["patient"],
        update_fields=["clinic", "urgency", "reasons", "updated_at"],
    )


def refresh_patient(patient_id: Any, clinic_id: Any) -> bool:
    """Recompute one patient's row; True when the patient needs attention."""
    found = patients_needing_attention(clinic_id, patient_id=patient_id)
    with transaction.atomic():
        if not found:
            PatientAttention.objects.filter(patient_id=patient_id).delete()
            return False
        save_rows([stored(found[0], clinic_id)])
    return True


def refresh_after_run(run_id: Any) -> None:
    """The update on write: never lets a problem here fail the run that triggered it.

    Also builds the run's reading (`webapp.recordings.reading`: its verdicts, pass count and
    statements, read by every page, list and export) and stores its progress point when it
    succeeded (`webapp.patients.progress_store`).
    """
    from webapp.patients.progress_store import store_after_run
    from webapp.recordings.models import AnalysisRun
    from webapp.recordings.reading import build_for

    try:
        with transaction.atomic():
            build_for(run_id)
    except Exception:  # the first reader builds it
        log.exception("reading not built after run %s", run_id)
    try:
        with transaction.atomic():
            store_after_run(run_id)
    except Exception:  # the next read of the patient's progress stores it
        log.exception("progress point not stored after run %s", run_id)
    try:
        with transaction.atomic():
            row = (
                AnalysisRun.objects.filter(pk=run_id)
                .values("recording__patient_id", "recording__clinic_id")
                .first()
            )
            if row is not None:
                refresh_patient(row["recording__patient_id"], row["recording__clinic_id"])
    except Exception:  # the beat refresh catches up
        log.exception("attention list not refreshed after run %s", run_id)


def refresh_clinic(clinic_id: Any) -> int:
    """Recompute every row of a clinic; returns how many patients need attention."""
    found = patients_needing_attention(clinic_id)
    rows = [stored(entry, clinic_id) for entry in found]
    with transaction.atomic():
        PatientAttention.objects.filter(clinic_id=clinic_id).exclude(
            patient_id__in=[row.patient_id for row in rows]
        ).delete()
        save_rows(rows)
    return len(rows)


def refresh_all() -> int:
    return sum(refresh_clinic(pk) for pk in Clinic.objects.values_list("pk", flat=True))


def read_page(clinic_id: Any, page_number: Any, per_page: int) -> Page:
    """One page of the clinic's stored list, most urgent first, with names (two queries)."""
    rows = (
        PatientAttention.objects.filter(
            clinic_id=clinic_id,
            patient__archived_at__isnull=True,
            patient__deleted_at__isnull=True,
        )
        .select_related("patient")
        .only("patient__id", "patient__display_name", "reasons", "urgency", "clinic_id")
        .order_by("-urgency", "patient_id")
    )
    return Paginator(rows, per_page).get_page(page_number)
