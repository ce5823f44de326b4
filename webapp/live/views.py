"""The live page (a therapist watching, or the patient), its status JSON, "replay as live",
starting a live session from the patient's page, and the therapist's read-only watch page."""

from __future__ import annotations

from typing import Any

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.core.exceptions import PermissionDenied
from django.http import Http404, HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import redirect, render
from django.views.decorators.cache import never_cache
from django.views.decorators.http import require_POST

from webapp.accounts.permissions import get_patient_for_user, get_recording_for_user
from webapp.audit import log
from webapp.live import services
from webapp.live.models import LiveSession
from webapp.recordings.models import AnalysisRun, RunStatus


def _session(request: HttpRequest, pk: Any) -> LiveSession:
    live = services.session_for(request.user, pk)
    if live is None:
        raise Http404("No such live session.")
    return live


@login_required
def page(request: HttpRequest, pk: Any) -> HttpResponse:
    live = _session(request, pk)
    return render(request, "live/page.html", {"live": live})


@never_cache
@login_required
def status(request: HttpRequest, pk: Any) -> JsonResponse:
    """The session's state and, once the stored recording is analysed, the offline figures."""
    live = _session(request, pk)
    body: dict[str, Any] = {"status": live.status, "summary": live.summary, "offline": None}
    if live.recording_id is not None:
        run = AnalysisRun.objects.filter(recording_id=live.recording_id).order_by("-created_at")
        body["recording"] = str(live.recording_id)
        body["offline"] = offline_figures(run.first())
    return JsonResponse(body)


def offline_figures(run: AnalysisRun | None) -> dict[str, Any] | None:
    """The figures the live page shows beside its own: repetitions, scores, overall score."""
    if run is None:
        return None
    out: dict[str, Any] = {"status": run.status, "progress": run.progress}
    result = run.result if run.status == RunStatus.SUCCEEDED else None
    if result is not None:
        out["repetitions"] = [
            {"start": r.start, "end": r.end, "score": r.score} for r in result.repetitions
        ]
        out["score"] = result.score
    return out


@login_required
@require_POST
def replay(request: HttpRequest, pk: Any) -> HttpResponse:
    """Stream a stored recording through the live path (a new replay session)."""
    recording = get_recording_for_user(request, pk)
    if recording.exercise is None:
        raise Http404("The recording has no exercise to align with.")
    if recording.exercise.active_model_id is None:  # every frame is aligned with the model
        messages.error(request, services.NOT_BUILT)
        return redirect("recordings:detail", pk=recording.pk)
    live = services.create_session(
        patient=recording.patient, exercise=recording.exercise, user=request.user,
        replay_of=recording,
    )  # fmt: skip
    return redirect("live:page", pk=live.pk)


@login_required
@require_POST
def start(request: HttpRequest, pk: Any) -> HttpResponse:
    """Open a live session for one of the patient's prescribed exercises that has a model, then
    its live page (where the capture system's frames will show)."""
    if not request.user.is_staff_member:
        raise PermissionDenied("Live sessions are started by the clinic's staff.")
    patient = get_patient_for_user(request, pk)  # a read of the patient, even when refused
    chosen = request.POST.get("exercise", "")
    exercise = next((e for e in services.startable_exercises(patient) if str(e.pk) == chosen), None)
    if exercise is None:
        messages.error(request, "Choose one of the exercises offered for a live session.")
        return redirect("patients:detail", pk=patient.pk)
    live = services.create_session(patient=patient, exercise=exercise, user=request.user)
    log.record(request, "create", live, patient_id=patient.pk)
    return redirect("live:page", pk=live.pk)


@login_required
def watch(request: HttpRequest, pk: Any) -> HttpResponse:
    """Follow a session as it runs, without sending anything: a therapist of the patient's
    clinic only (another clinic's gets 404, a patient 403)."""
    if not request.user.is_staff_member:
        raise PermissionDenied("Watching is for the clinic's staff.")
    live = _session(request, pk)
    log.record(request, "read", live, patient_id=live.patient_id)
    return render(request, "live/page.html", {"live": live, "watching": True})
