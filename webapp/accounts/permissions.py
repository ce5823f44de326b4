"""The one place that decides who sees which clinical object.

Therapists and clinic admins see their clinic's objects; a patient sees only their own record;
nobody sees another clinic's objects. Objects out of reach answer 404 (their existence is not
revealed); actions a role may not take on a visible object answer 403.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import wraps
from typing import Any, TypeVar

from django.core.exceptions import PermissionDenied
from django.db.models import Model, QuerySet
from django.http import HttpRequest, HttpResponse
from django.shortcuts import get_object_or_404

from webapp.accounts.models import Role, User
from webapp.audit import log
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun, Recording

Row = TypeVar("Row", bound=Model)


def clinic_scoped(rows: QuerySet[Row], user: User, own: str | None = None) -> QuerySet[Row]:
    """The one clinic-scope guard: of ``rows``, those of the user's clinic (none for a visitor
    or an account without a clinic); for a patient, also only their own, the rows whose
    ``own`` lookup (e.g. ``"patient__user"``) is them. ``own`` None: rows every member of the
    clinic may see (its exercises)."""
    if not user.is_authenticated or user.clinic_id is None:
        return rows.none()
    scoped = rows.filter(clinic_id=user.clinic_id)
    if own is not None and user.is_patient:
        return scoped.filter(**{own: user})
    return scoped


def visible_patients(user: User) -> QuerySet[Patient]:
    return clinic_scoped(Patient.objects.all(), user, own="user")


def visible_exercises(user: User) -> QuerySet[Exercise]:
    return clinic_scoped(Exercise.objects.all(), user)


def visible_recordings(user: User) -> QuerySet[Recording]:
    return clinic_scoped(Recording.objects.all(), user, own="patient__user")


def get_patient_for_user(request: HttpRequest, pk: Any, audit: bool = True) -> Patient:
    patient = get_object_or_404(visible_patients(request.user), pk=pk)
    if audit:
        log.record(request, "read", patient, patient_id=patient.pk)
    return patient


def get_exercise_for_user(request: HttpRequest, pk: Any) -> Exercise:
    return get_object_or_404(visible_exercises(request.user), pk=pk)


def get_recording_for_user(request: HttpRequest, pk: Any, audit: bool = True) -> Recording:
    recording = get_object_or_404(
        visible_recordings(request.user).select_related("patient", "exercise"), pk=pk
    )
    if audit:
        log.record(request, "read", recording, patient_id=recording.patient_id)
    return recording


def get_run_for_user(request: HttpRequest, pk: Any) -> AnalysisRun:
    recordings = visible_recordings(request.user)
    return get_object_or_404(AnalysisRun.objects.filter(recording__in=recordings), pk=pk)


def require_staff(view: Callable[..., HttpResponse]) -> Callable[..., HttpResponse]:
    """Only therapists and clinic admins (patients get 403)."""

    @wraps(view)
    def wrapped(request: HttpRequest, *args: Any, **kwargs: Any) -> HttpResponse:
        if not request.user.is_staff_member or request.user.clinic_id is None:
            raise PermissionDenied("Only clinic staff can do this.")
        return view(request, *args, **kwargs)

    return wrapped


def require_clinic_admin(view: Callable[..., HttpResponse]) -> Callable[..., HttpResponse]:
    """Only the clinic's admins (therapists and patients get 403)."""

    @wraps(view)
    def wrapped(request: HttpRequest, *args: Any, **kwargs: Any) -> HttpResponse:
        if request.user.role != Role.CLINIC_ADMIN or request.user.clinic_id is None:
            raise PermissionDenied("Only the clinic admin can do this.")
        return view(request, *args, **kwargs)

    return wrapped
