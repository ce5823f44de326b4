"""Which exercises an upload may be of: the patient's current prescriptions, else the clinic's.

Used by the upload form, the confirmation of a recognised exercise and the worker that recognises
it (`workers/recognition.py`), so this module imports models only and enqueues nothing.
"""

from __future__ import annotations

from django.db.models import Q, QuerySet
from django.utils import timezone

from webapp.exercises.models import Exercise
from webapp.patients.models import Patient


def with_key_poses(exercises: QuerySet[Exercise]) -> QuerySet[Exercise]:
    """Active exercises whose tutor's key poses are marked: the ones a model exists (or is built)
    for, the same rule as `webapp.recordings.recovery.analysable` (which imports the services,
    so the worker cannot import it)."""
    return exercises.filter(archived_at__isnull=True).exclude(tutor_landmark_frames=[])


def prescribed_exercises(patient: Patient, exercises: QuerySet[Exercise]) -> QuerySet[Exercise]:
    """Those of `exercises` prescribed to the patient and not ended before today."""
    today = timezone.localdate()
    current = Q(prescriptions__end_date__isnull=True) | Q(prescriptions__end_date__gte=today)
    return exercises.filter(current, prescriptions__patient=patient).distinct()


def offered_exercises(patient: Patient, exercises: QuerySet[Exercise]) -> QuerySet[Exercise]:
    """The patient's prescribed exercises among `exercises`; all of them when none is prescribed
    (a new patient can still have a recording analysed)."""
    prescribed = prescribed_exercises(patient, exercises)
    return prescribed if prescribed.exists() else exercises


def recognition_candidates(patient: Patient) -> QuerySet[Exercise]:
    """The exercises the worker compares an upload with: the patient's prescribed exercises with
    a tutor and key poses, or every such exercise of the clinic."""
    clinic = with_key_poses(Exercise.objects.filter(clinic_id=patient.clinic_id))
    return offered_exercises(patient, clinic.exclude(tutor_file="")).order_by("name")
