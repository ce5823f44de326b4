from __future__ import annotations

import json

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.core.exceptions import ValidationError
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import redirect, render
from django.views.decorators.cache import never_cache
from django.views.decorators.http import require_POST
from rest_framework.renderers import JSONRenderer

from webapp.accounts.permissions import (
    get_recording_for_user,
    require_staff,
)
from webapp.api.views import RecordingResult
from webapp.dashboard import patient_result
from webapp.recordings import recovery_views, services, warmup
from webapp.recordings.corrections import apply_corrections, corrections_of
from webapp.recordings.forms import UploadForm, upload_choices
from webapp.recordings.models import AnalysisRun
from webapp.recordings.notes import NoteForm, notes_of
from webapp.recordings.reading import reading_of
from webapp.recordings.recognition import recognition_status
from webapp.recordings.uploads import accept_upload


def upload_form(request: HttpRequest) -> UploadForm:
    choices = upload_choices(request.user)  # a patient: themselves, their prescribed exercises
    initial = {"patient": request.GET.get("patient"), "exercise": request.GET.get("exercise")}
    if request.method == "POST":
        return UploadForm(request.POST, request.FILES, **choices)
    return UploadForm(initial=initial, **choices)


@login_required
def upload(request: HttpRequest) -> HttpResponse:
    form = upload_form(request)
    if request.method == "POST" and form.is_valid():
        recording, _ = accept_upload(form.parsed, form.cleaned_data, request.user)
        if recording.exercise_id is None:  # recognised by a worker; confirmed on its page
            messages.info(request, "Recording uploaded. Please confirm which exercise it is below.")
            return redirect("recordings:detail", pk=recording.pk)
        messages.success(
            request, "Recording uploaded. The analysis runs in the background: progress below."
        )
        return redirect("recordings:detail", pk=recording.pk)
    status = 400 if request.method == "POST" else 200
    warmup.start()  # while the person chooses a file
    return render(request, "recordings/upload.html", {"form": form}, status=status)


@login_required
def detail(request: HttpRequest, pk) -> HttpResponse:
    recording = get_recording_for_user(request, pk)
    if request.user.is_patient:  # a lay result page, not the therapist's technical one
        return patient_result.page(request, recording)
    runs = list(recording.runs.all())
    run = runs[0] if runs else None
    context = {"recording": recording, "run": run, "runs": runs, "reading": reading_of(run)}
    context["notes"] = notes_of(recording)
    if request.user.is_staff_member:
        context["move_form"] = recovery_views.move_form(request, recording)
        context["note_form"] = NoteForm()
    return render(request, "recordings/detail.html", context)


def run_status(run: AnalysisRun | None) -> dict:
    if run is None:
        return {"status": None, "progress": 0, "stage": ""}
    return {
        "run": str(run.pk),
        "status": run.status,
        "stage": run.stage,
        "progress": run.progress,
        "error": run.user_error,
    }


@never_cache
@login_required
def status(request: HttpRequest, pk) -> JsonResponse:
    recording = get_recording_for_user(request, pk, audit=False)  # polled every second
    run = recording.runs.first()
    if run is None:  # no analysis yet: how far the worker's recognition of the exercise is
        return JsonResponse(recognition_status(recording))
    return JsonResponse(run_status(run))


@login_required
@require_staff
@require_POST
def rerun(request: HttpRequest, pk) -> HttpResponse:
    recording = get_recording_for_user(request, pk)
    if recording.exercise is None:
        messages.error(request, "Choose the exercise before analysing this recording.")
    else:
        services.start_analysis(recording)
        messages.success(request, "A new analysis has started; earlier results are kept.")
    return redirect("recordings:detail", pk=recording.pk)


# One JSON door for a run's result: the page's `result.json` is answered by the API's own
# view (`/api/v1/recordings/{id}/result/`, in the interface contract), as JSON, behind the
# page's sign-in.
api_result = RecordingResult.as_view(renderer_classes=[JSONRenderer])


@never_cache
@login_required
def result(request: HttpRequest, pk) -> HttpResponse:
    """The result of the recording's newest run, exactly as `/api/v1/recordings/{id}/result/`."""
    return api_result(request, pk=pk)


@login_required
@require_staff
@require_POST
def label(request: HttpRequest, pk) -> HttpResponse:
    """The page's form: a therapist's verdict on one repetition (``index``, ``passed`` 1 or 0),
    stored as the corrections API stores it, so every page and export counts it at once."""
    recording = get_recording_for_user(request, pk)
    run = recording.latest_succeeded_run()
    index, passed = request.POST.get("index", ""), request.POST.get("passed", "")
    if run is None or not index.isdigit() or passed not in ("0", "1"):
        messages.error(request, "That verdict could not be saved: choose a repetition again.")
        return redirect("recordings:detail", pk=recording.pk)
    verdict = {"repetitions": [{"index": int(index), "passed": passed == "1"}]}
    try:
        apply_corrections(run, verdict, request.user)
    except ValidationError as error:
        messages.error(request, " ".join(error.messages))
    else:
        word = "passed" if passed == "1" else "not passed"
        messages.success(request, f"Repetition {int(index) + 1} marked {word}.")
    return redirect("recordings:detail", pk=recording.pk)


@never_cache
@login_required
@require_staff
def corrections(request: HttpRequest, pk) -> JsonResponse:
    """GET the therapist corrections of the latest analysis; POST (JSON) adds corrections."""
    recording = get_recording_for_user(request, pk)
    run = recording.latest_succeeded_run()
    if request.method == "POST":
        if run is None:
            return JsonResponse({"detail": "The recording has no finished analysis."}, status=400)
        try:
            saved = apply_corrections(run, json.loads(request.body or b"null"), request.user)
        except json.JSONDecodeError:
            return JsonResponse({"detail": "The body is not JSON."}, status=400)
        except ValidationError as error:
            return JsonResponse(error.message_dict, status=400)
        return JsonResponse({"saved": saved, **corrections_of(run)})
    return JsonResponse(corrections_of(run) if run else {"run": None})
