from __future__ import annotations

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import redirect, render
from django.views.decorators.cache import never_cache
from django.views.decorators.http import require_POST

from webapp.accounts.permissions import (
    get_recording_for_user,
    require_staff,
    visible_exercises,
    visible_patients,
)
from webapp.recordings import services
from webapp.recordings.forms import UploadForm
from webapp.recordings.models import AnalysisRun
from webapp.recordings.uploads import store_recording


def upload_form(request: HttpRequest) -> UploadForm:
    patients = visible_patients(request.user).filter(archived_at__isnull=True)
    exercises = visible_exercises(request.user).filter(archived_at__isnull=True)
    initial = {"patient": request.GET.get("patient"), "exercise": request.GET.get("exercise")}
    if request.method == "POST":
        return UploadForm(request.POST, request.FILES, patients=patients, exercises=exercises)
    return UploadForm(initial=initial, patients=patients, exercises=exercises)


@login_required
def upload(request: HttpRequest) -> HttpResponse:
    form = upload_form(request)
    if request.method == "POST" and form.is_valid():
        data = form.cleaned_data
        recording, _ = store_recording(
            form.parsed, patient=data["patient"], exercise=data["exercise"], user=request.user,
            pain_score=data["pain_score"], note=data["note"],
        )
        messages.success(request, "Recording uploaded; the analysis has started.")
        return redirect("recordings:detail", pk=recording.pk)
    status = 400 if request.method == "POST" else 200
    return render(request, "recordings/upload.html", {"form": form}, status=status)


@login_required
def detail(request: HttpRequest, pk) -> HttpResponse:
    recording = get_recording_for_user(request, pk)
    runs = list(recording.runs.all())
    context = {"recording": recording, "run": runs[0] if runs else None, "runs": runs}
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
    return JsonResponse(run_status(recording.runs.first()))


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
