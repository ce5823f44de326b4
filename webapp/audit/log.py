"""Recording audit events from views, API endpoints and (for writes) model signals."""

from __future__ import annotations

from django.http import HttpRequest

from webapp.audit.models import AuditEvent


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
        path=request.get_full_path()[:300],
        ip_address=client_ip(request),
        via=channel(request),
    )
