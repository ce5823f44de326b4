from __future__ import annotations

from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import render
from django.views.decorators.cache import never_cache
from django.views.decorators.http import require_GET

from webapp.accounts.permissions import visible_patients
from webapp.dashboard import health, patient_result
from webapp.dashboard import home as parts
from webapp.live.services import under_way


@require_GET
@never_cache
def healthz(request: HttpRequest) -> JsonResponse:
    database = health.database_ok()
    broker = health.broker_ok()
    healthy = database and broker is not False
    body = {"status": "ok" if healthy else "unavailable", "database": database, "broker": broker}
    return JsonResponse(body, status=200 if healthy else 503)


@require_GET
@never_cache
@login_required
def home(request: HttpRequest) -> HttpResponse:
    """The therapist's (or patient's) home; `?format=json` is what the page polls for live parts."""
    user = request.user
    if request.GET.get("format") == "json":
        return JsonResponse(parts.live_json(user))
    context = {
        "recent": parts.recent_recordings(user),
        "active": parts.active_runs(user),
        "active_limit": parts.ACTIVE_RUNS,
    }
    if user.is_patient:
        extra = patient_context(user, context["recent"])
        return render(request, "dashboard/patient_home.html", context | extra)
    context["attention"] = parts.attention_page(user, request.GET.get("attention_page"))
    context["my_patients"] = parts.my_patients(user)
    context["live_under_way"] = under_way(user)
    return render(request, "dashboard/home.html", context)


def patient_context(user, recent: list) -> dict:
    patient = visible_patients(user).first()
    if patient is None:
        return {"patient": None, "prescriptions": []}
    last = patient_result.last_session(recent)
    return {"patient": patient, "last": last, **parts.patient_plan(patient)}
