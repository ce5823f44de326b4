"""Recording audit events from views and API endpoints."""

from __future__ import annotations

from django.http import HttpRequest

from webapp.audit.models import AuditEvent


def client_ip(request: HttpRequest) -> str | None:
    # Behind a reverse proxy, configure it to set REMOTE_ADDR (e.g. gunicorn --forwarded-allow-ips).
    return request.META.get("REMOTE_ADDR") or None


def record(request: HttpRequest, action: str, obj, patient_id=None) -> None:
    user = request.user
    if not user.is_authenticated or user.clinic_id is None:
        return
    AuditEvent.objects.create(
        clinic_id=user.clinic_id,
        user=user,
        username=user.get_username(),
        action=action,
        object_type=type(obj).__name__,
        object_id=str(obj.pk),
        patient_id=patient_id,
        path=request.get_full_path()[:300],
        ip_address=client_ip(request),
    )
