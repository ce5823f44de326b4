"""Write events for patient data, raised by model signals inside a web or API request.

Views do not have to remember to log writes: saving or deleting any model that holds patient
data during a request records who did it. Writes made outside a request (the analysis worker,
beat tasks, management commands) are the system's own and are not logged here.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from django.db.models.signals import post_delete, post_save

from webapp.audit import log
from webapp.audit.context import current_request


def via_run(obj) -> Any:
    from webapp.recordings.models import Recording

    return Recording.objects.filter(runs=obj.run_id).values_list("patient_id", flat=True).first()


def patient_of_run(obj) -> Any:
    from webapp.recordings.models import Recording

    return (
        Recording.objects.filter(pk=obj.recording_id).values_list("patient_id", flat=True).first()
    )


def audited_models() -> dict[type, tuple[Callable[[Any], Any], bool]]:
    """Model → (how to find its patient, whether updates are logged or only creation)."""
    from webapp.patients.models import Patient, PerformanceLevel, Prescription
    from webapp.recordings.models import (
        AnalysisRun,
        AssessmentCorrection,
        LandmarkCorrection,
        Recording,
        RepetitionLabel,
    )

    by_patient_field = (lambda obj: obj.patient_id, True)
    return {
        Patient: (lambda obj: obj.pk, True),
        Prescription: by_patient_field,
        PerformanceLevel: by_patient_field,
        Recording: by_patient_field,
        # A run's progress is written many times by the worker; its creation (a re-run) is the act.
        AnalysisRun: (patient_of_run, False),
        LandmarkCorrection: (via_run, True),
        AssessmentCorrection: (via_run, True),
        RepetitionLabel: (via_run, True),
    }


def on_save(sender, instance, created: bool, **kwargs) -> None:
    request = current_request.get()
    if request is None or kwargs.get("raw"):
        return
    patient_of, log_updates = AUDITED[sender]
    if created or log_updates:
        log.record(request, "create" if created else "update", instance, patient_of(instance))


def on_delete(sender, instance, **kwargs) -> None:
    request = current_request.get()
    if request is None:
        return
    patient_of, _ = AUDITED[sender]
    patient_id = instance.pk if sender.__name__ == "Patient" else None
    try:
        patient_id = patient_id or patient_of(instance)
    except Exception:  # the parent row may already be gone in a cascade
        patient_id = None
    log.record(request, "delete", instance, patient_id)


AUDITED: dict[type, tuple[Callable[[Any], Any], bool]] = {}


def connect() -> None:
    AUDITED.update(audited_models())
    for model in AUDITED:
        post_save.connect(on_save, sender=model, dispatch_uid=f"audit-save-{model.__name__}")
        post_delete.connect(on_delete, sender=model, dispatch_uid=f"audit-del-{model.__name__}")
