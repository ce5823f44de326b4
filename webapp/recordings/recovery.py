"""Recovering from a mistaken upload: move a recording to another exercise or patient of the
clinic (it is analysed again), delete it (soft: hidden everywhere) and restore it (clinic admins).

Every change is one audit event (`webapp.audit.log`): a move is an "update" of the recording for
its new patient (and one for the old patient when the patient changes), a deletion a "delete", a
restore an "update" made from the restore address. The rows are written with `update()`, so the
model signals do not log the same act a second time. The stored attention list of the patients
involved is recomputed at once: a failed analysis no longer flags a recording that was moved
(its newest run is then the new one) or deleted.
"""

from __future__ import annotations

import logging
from typing import Any

from django.core.exceptions import ValidationError
from django.db import transaction
from django.db.models import QuerySet
from django.http import HttpRequest
from django.utils import timezone

from webapp.audit import log as audit
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient
from webapp.recordings import services
from webapp.recordings.models import Recording
from webapp.recordings.storage import DamagedRecordingError, read_verified
from webapp.recordings.uploads import check_not_duplicate, check_skeleton, stored_motion

log = logging.getLogger(__name__)


def analysable(exercises: QuerySet[Exercise]) -> QuerySet[Exercise]:
    """The exercises a recording can be analysed against: active, with the tutor's key poses
    marked (the exercise's model is built from them, at the latest by the first analysis)."""
    return exercises.filter(archived_at__isnull=True).exclude(tutor_landmark_frames=[])


def check_analysable(exercise: Exercise) -> None:
    """Refuse, in plain words, an exercise whose recordings cannot be analysed yet."""
    if exercise.archived_at is not None:
        raise ValidationError(f"{exercise.name} is archived; choose a current exercise.")
    if not exercise.tutor_landmark_frames:
        raise ValidationError(
            f"{exercise.name} has no key poses yet, so its recordings cannot be analysed. "
            "A therapist marks them on the exercise's page first; then upload the recording."
        )


def check_fits(recording: Recording, exercise: Exercise) -> None:
    """The stored recording's skeleton must map onto the new exercise's (as for an upload)."""
    try:
        content = read_verified(recording)
    except DamagedRecordingError as error:
        raise ValidationError(str(error)) from error
    check_skeleton(stored_motion(recording.file.name, content), exercise)


def check_move(
    recording: Recording, exercise: Exercise | None, patient: Patient | None
) -> dict[str, Any]:
    """The fields that change (possibly none); ValidationError {field: reason} when one cannot."""
    changes: dict[str, Any] = {}
    if exercise is not None and exercise.pk != recording.exercise_id:
        try:
            check_analysable(exercise)
            check_fits(recording, exercise)
        except ValidationError as error:
            raise ValidationError({"exercise": error.messages}) from error
        changes["exercise"] = exercise
    if patient is not None and patient.pk != recording.patient_id:
        try:
            check_not_duplicate(patient, recording.checksum)
        except ValidationError as error:
            raise ValidationError({"patient": error.messages}) from error
        changes["patient"] = patient
    return changes


def move_recording(request: HttpRequest, recording: Recording, changes: dict[str, Any]):
    """Apply `check_move`'s changes and queue a new analysis (None when nothing changed or the
    recording still waits for its exercise). Earlier runs are kept, as for "Analyse again"."""
    if not changes:
        return None
    old_patient = recording.patient_id
    with transaction.atomic():
        Recording.objects.filter(pk=recording.pk).update(**changes)
        for field, value in changes.items():
            setattr(recording, field, value)
        run = services.start_analysis(recording) if recording.exercise_id else None
        audit.record(request, "update", recording, patient_id=recording.patient_id)
        if old_patient != recording.patient_id:
            audit.record(request, "update", recording, patient_id=old_patient)
        refresh_attention(recording.clinic_id, {old_patient, recording.patient_id})
    return run


def delete_recording(request: HttpRequest, recording: Recording) -> None:
    """Hide the recording from every page, list, export and the API (a clinic admin can restore
    it); its file, runs and results are kept."""
    with transaction.atomic():
        Recording.objects.filter(pk=recording.pk).update(
            deleted_at=timezone.now(), deleted_by=request.user
        )
        audit.record(request, "delete", recording, patient_id=recording.patient_id)
        refresh_attention(recording.clinic_id, {recording.patient_id})


def deleted_recordings(clinic_id: Any) -> QuerySet[Recording]:
    """The clinic's deleted recordings whose patient is not deleted, newest deletion first."""
    return (
        Recording.all_objects.filter(
            clinic_id=clinic_id, deleted_at__isnull=False, patient__deleted_at__isnull=True
        )
        .select_related("patient", "exercise", "deleted_by")
        .order_by("-deleted_at")
    )


def restore_recording(request: HttpRequest, recording: Recording) -> None:
    with transaction.atomic():
        Recording.all_objects.filter(pk=recording.pk).update(deleted_at=None, deleted_by=None)
        audit.record(request, "update", recording, patient_id=recording.patient_id)
        refresh_attention(recording.clinic_id, {recording.patient_id})


def refresh_attention(clinic_id: Any, patient_ids: set[Any]) -> None:
    """Recompute the patients' rows of the stored attention list (the beat task would catch up a
    failure here; it never undoes the change)."""
    from webapp.dashboard.precompute import refresh_patient

    for patient_id in patient_ids:
        try:
            refresh_patient(patient_id, clinic_id)
        except Exception:  # a savepoint: the move or deletion itself stands
            log.exception("attention list not refreshed for patient %s", patient_id)
