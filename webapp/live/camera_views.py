"""The camera page of a prescribed exercise: the patient exercises in front of their own camera
(phone or laptop), or a therapist opens it for a patient in the room on the clinic's computer.

The page finds the body in the browser (`webapp/static/js/camera_pose.js`) and sends only the
body's landmarks to a live session (`webapp.live.camera`); the pictures stay on the device.
Pressing Start opens a new live session (`start`), so loading the page leaves no session behind.
"""

from __future__ import annotations

from typing import Any

from django.contrib.auth.decorators import login_required
from django.http import Http404, HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import render
from django.urls import reverse
from django.views.decorators.http import require_POST

from webapp.accounts.permissions import visible_patients
from webapp.audit import log
from webapp.live import services
from webapp.patients.models import Prescription

FPS = 15  # frames a second sent to the session: the landmarks are resampled to this rate


def _prescription(request: HttpRequest, pk: Any) -> Prescription:
    """The prescription, when its patient is the signed-in patient or one of the staff member's
    clinic (another's: 404)."""
    found = (
        Prescription.objects.filter(pk=pk, patient__in=visible_patients(request.user))
        .select_related("patient", "exercise")
        .first()
    )
    if found is None:
        raise Http404("No such prescribed exercise.")
    return found


@login_required
def page(request: HttpRequest, pk: Any) -> HttpResponse:
    prescription = _prescription(request, pk)
    exercise = prescription.exercise
    context = {
        "prescription": prescription,
        "patient": prescription.patient,
        "exercise": exercise,
        "ready": exercise.followable_live,
        "for_patient": request.user.is_patient,
        "fps": FPS,
        "start_url": reverse("camera:start", args=[prescription.pk]),
    }
    return render(request, "live/camera.html", context)


@login_required
@require_POST
def start(request: HttpRequest, pk: Any) -> JsonResponse:
    """A new live session for the prescription: where the page sends its landmarks."""
    prescription = _prescription(request, pk)
    exercise = prescription.exercise
    if not exercise.followable_live:
        return JsonResponse({"error": NOT_READY}, status=409)
    live = services.create_session(
        patient=prescription.patient, exercise=exercise, user=request.user
    )
    log.record(request, "create", live, patient_id=prescription.patient_id)
    return JsonResponse(
        {
            "session": str(live.pk),
            "ws": live.ws_path,
            "fps": FPS,
            "status_url": reverse("live:status", args=[live.pk]),
        }
    )


NOT_READY = (
    "This exercise cannot be followed live yet: your therapist has not finished preparing it."
)
