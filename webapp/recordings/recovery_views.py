"""Pages that undo a mistaken upload: move a recording (staff), delete it after a confirmation
(staff), and the clinic admin's list of deleted recordings with a Restore button."""

from __future__ import annotations

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse
from django.shortcuts import get_object_or_404, redirect, render
from django.views.decorators.http import require_POST

from webapp.accounts.permissions import get_recording_for_user, require_clinic_admin, require_staff
from webapp.recordings import recovery
from webapp.recordings.forms import MoveForm


def move_form(request: HttpRequest, recording, data=None) -> MoveForm:
    initial = {"exercise": recording.exercise_id, "patient": recording.patient_id}
    form = MoveForm(data, initial=initial, recording=recording, user=request.user)
    return form.offer_analysable_only()


@login_required
@require_staff
def move(request: HttpRequest, pk) -> HttpResponse:
    """GET: the form alone; POST (also from the recording page's form): move and re-analyse."""
    recording = get_recording_for_user(request, pk)
    form = move_form(request, recording, request.POST if request.method == "POST" else None)
    if request.method == "POST" and form.is_valid():
        run = recovery.move_recording(request, recording, form.changes)
        if not form.changes:
            messages.info(request, "The recording already has this exercise and patient.")
        elif run is None:
            messages.success(request, "Recording moved.")
        else:
            messages.success(request, "Recording moved. It is analysed again: progress below.")
        return redirect("recordings:detail", pk=recording.pk)
    status = 400 if request.method == "POST" else 200
    context = {"recording": recording, "move_form": form}
    return render(request, "recordings/move.html", context, status=status)


@login_required
@require_staff
def delete(request: HttpRequest, pk) -> HttpResponse:
    """GET: the confirmation page; POST: delete (hidden at once, restorable by a clinic admin)."""
    recording = get_recording_for_user(request, pk)
    if request.method == "POST":
        recovery.delete_recording(request, recording)
        messages.success(
            request,
            f"Recording deleted ({recording.exercise or 'no exercise'}, "
            f"{recording.uploaded_at:%d %b %Y}). A clinic admin can restore it.",
        )
        return redirect("patients:detail", pk=recording.patient_id)
    return render(request, "recordings/delete.html", {"recording": recording})


@login_required
@require_clinic_admin
def deleted(request: HttpRequest) -> HttpResponse:
    recordings = recovery.deleted_recordings(request.user.clinic_id)[:200]
    return render(request, "recordings/deleted.html", {"recordings": recordings})


@login_required
@require_clinic_admin
@require_POST
def restore(request: HttpRequest, pk) -> HttpResponse:
    recording = get_object_or_404(recovery.deleted_recordings(request.user.clinic_id), pk=pk)
    recovery.restore_recording(request, recording)
    messages.success(
        request, f"Recording of {recording.patient.display_name} restored: it is shown again."
    )
    return redirect("recordings:deleted")
