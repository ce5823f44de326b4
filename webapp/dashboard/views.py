from __future__ import annotations

from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import render
from django.views.decorators.cache import never_cache
from django.views.decorators.http import require_GET

from webapp.dashboard import health
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient


@require_GET
@never_cache
def healthz(request: HttpRequest) -> JsonResponse:
    database = health.database_ok()
    broker = health.broker_ok()
    healthy = database and broker is not False
    body = {"status": "ok" if healthy else "unavailable", "database": database, "broker": broker}
    return JsonResponse(body, status=200 if healthy else 503)


@login_required
def home(request: HttpRequest) -> HttpResponse:
    user = request.user
    patients = Patient.objects.filter(clinic=user.clinic, archived_at__isnull=True)
    if user.is_patient:
        patients = patients.filter(user=user)
    exercises = Exercise.objects.filter(clinic=user.clinic, archived_at__isnull=True)
    context = {"patients": patients[:20], "exercises": exercises}
    return render(request, "dashboard/home.html", context)
