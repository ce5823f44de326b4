"""Recording audit events from views, API endpoints and (for writes) model signals."""

from __future__ import annotations

import datetime

from django.http import HttpRequest
from django.utils import timezone

from webapp.audit.models import AuditEvent
from webapp.audit.words import describe

PATH_LENGTH = AuditEvent._meta.get_field("path").max_length
# A page's own fetches (the recording page's playback data) arrive within seconds of the page;
# a reader who comes back later, or a script fetching them alone, leaves an event of its own.
FOLD_WINDOW = datetime.timedelta(minutes=10)


def client_ip(request: HttpRequest) -> str | None:
    # Behind a reverse proxy, configure it to set REMOTE_ADDR (e.g. gunicorn --forwarded-allow-ips).
    return request.META.get("REMOTE_ADDR") or None


def channel(request: HttpRequest) -> str:
    """ "web" for a browser session, "token <prefix>" for a call with an API token."""
    token = getattr(request, "api_token", None) or getattr(
        getattr(request, "_request", None), "api_token", None
    )
    return f"token {token.prefix}" if token is not None else "web"


def clinic_of_patient(patient_id):
    """The clinic of a patient touched by a user of no clinic (a superuser in the admin)."""
    if patient_id is None:
        return None
    from webapp.patients.models import Patient

    return Patient.objects.filter(pk=patient_id).values_list("clinic_id", flat=True).first()


def record(request: HttpRequest, action: str, obj, patient_id=None) -> None:
    """One event for `obj`, done by the request's user; nothing for anonymous requests."""
    user = request.user
    if not user.is_authenticated:
        return
    clinic_id = user.clinic_id or clinic_of_patient(patient_id)
    if clinic_id is None:
        return
    AuditEvent.objects.create(
        clinic_id=clinic_id,
        user=user,
        username=user.get_username(),
        action=action,
        object_type=type(obj).__name__,
        object_id=str(obj.pk) if obj is not None else "",
        patient_id=patient_id,
        path=request.get_full_path()[:PATH_LENGTH],
        ip_address=client_ip(request),
        via=channel(request),
        description=describe(obj),
    )


def read_recently(request: HttpRequest, obj) -> bool:
    """Whether this user, on this channel, read `obj` within `FOLD_WINDOW`."""
    return AuditEvent.objects.filter(
        user=request.user,
        action=AuditEvent.Action.READ,
        object_type=type(obj).__name__,
        object_id=str(obj.pk),
        via=channel(request),
        at__gte=timezone.now() - FOLD_WINDOW,
    ).exists()


def record_page_part(request: HttpRequest, obj, patient_id=None) -> None:
    """A read that a page makes for the object it shows (one page view, one event): folded into
    the page's read of `obj` when there is one, an event of its own otherwise."""
    if request.user.is_authenticated and read_recently(request, obj):
        return
    record(request, "read", obj, patient_id=patient_id)
