"""The patient's page for one recording (`recordings:detail` branches here by role) and the effort
they give on it when the upload did not ask it (Borg CR10, 0–10)."""

from __future__ import annotations

from typing import Any

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.core.exceptions import PermissionDenied
from django.http import HttpRequest, HttpResponse
from django.shortcuts import redirect, render
from django.views.decorators.http import require_POST

from webapp.accounts.permissions import get_recording_for_user
from webapp.dashboard.lay_words import lay_result
from webapp.recordings.forms import EffortForm
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from webapp.recordings.notes import notes_of
from webapp.recordings.reading import reading_of


def last_session(recent: list[Recording]) -> dict[str, Any] | None:
    """The newest of the home page's recent recordings (annotated with their newest run) and,
    once that run has succeeded, its result in the patient's words (one query)."""
    if not recent:
        return None
    newest = recent[0]
    lay = None
    if newest.run_status == RunStatus.SUCCEEDED:
        run = AnalysisRun.objects.select_related("reading").get(pk=newest.run_id)
        result = run.result
        lay = lay_result(result, newest.exercise, reading_of(run)) if result is not None else None
    return {"recording": newest, "lay": lay}


def page(
    request: HttpRequest, recording: Recording, form: EffortForm | None = None
) -> HttpResponse:
    """The lay result: repetitions done and done well, a few tips, what went well."""
    run = recording.runs.first()
    lay = None
    if run is not None and run.status == RunStatus.SUCCEEDED and run.result is not None:
        lay = lay_result(run.result, recording.exercise, reading_of(run))
    context = {
        "recording": recording,
        "run": run,
        "lay": lay,
        "effort_form": form or EffortForm(instance=recording),
        "notes": notes_of(recording),
    }
    return render(request, "recordings/patient_result.html", context, status=400 if form else 200)


@login_required
@require_POST
def effort(request: HttpRequest, pk) -> HttpResponse:
    """Save how hard the session felt; only the patient themselves answers it."""
    if not request.user.is_patient:
        raise PermissionDenied("Only the patient says how hard a session felt.")
    recording = get_recording_for_user(request, pk)
    form = EffortForm(request.POST, instance=recording)
    if not form.is_valid():
        return page(request, recording, form)
    form.save()
    messages.success(request, "Thank you: your therapist will see how hard it felt.")
    return redirect("recordings:detail", pk=recording.pk)
