"""Playback data, charts page and reports (PDF and printable HTML).

Every view reaches its object through `webapp.accounts.permissions`, so another clinic's
recording or patient answers 404 and a patient sees only their own.
"""

from __future__ import annotations

from django.contrib.auth.decorators import login_required
from django.core.files.storage import default_storage
from django.http import FileResponse, HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import redirect, render

from webapp.accounts.permissions import get_patient_for_user, get_recording_for_user
from webapp.audit import log
from webapp.patients.adherence import patient_adherence
from webapp.patients.goals import chart_lines
from webapp.reports import content, playback, services

NOT_READY = "This recording has no playback data yet (the analysis has not succeeded)."


def playback_or_none(request: HttpRequest, pk):
    # Playback data is patient data: audited, as part of the recording page that fetches it.
    recording = get_recording_for_user(request, pk, audit=False)
    log.record_page_part(request, recording, patient_id=recording.patient_id)
    run = recording.latest_succeeded_run()
    if run is None:
        return None, None
    try:
        return run, playback.load_arrays(run)
    except (OSError, ValueError, KeyError):
        return run, None


@login_required
def playback_json(request: HttpRequest, pk) -> JsonResponse:
    run, arrays = playback_or_none(request, pk)
    if arrays is None or "patient_positions" not in arrays:
        return JsonResponse({"available": False, "message": NOT_READY})
    data = playback.description(run, arrays)
    data["available"] = True
    response = JsonResponse(data)
    response["Cache-Control"] = "private, no-cache"
    return response


@login_required
def playback_bin(request: HttpRequest, pk) -> HttpResponse:
    run, arrays = playback_or_none(request, pk)
    if arrays is None or "patient_positions" not in arrays:
        return HttpResponse(NOT_READY, status=409, content_type="text/plain")
    response = HttpResponse(
        playback.positions_bytes(arrays), content_type="application/octet-stream"
    )
    response["Cache-Control"] = "private, no-cache"
    response["X-Run"] = str(run.pk)
    return response


def pending(request: HttpRequest) -> HttpResponse:
    return render(request, "reports/pending.html", {"next": request.get_full_path()}, status=202)


def pdf_response(name: str, filename: str) -> FileResponse:
    return FileResponse(
        default_storage.open(name, "rb"),
        as_attachment=True,
        filename=filename,
        content_type="application/pdf",
    )


@login_required
def recording_pdf(request: HttpRequest, pk) -> HttpResponse:
    recording = get_recording_for_user(request, pk)
    name = services.recording_report_name(recording)
    if not services.request_report("recording", recording.pk, name):
        return pending(request)
    return pdf_response(name, f"recording-{recording.pk}.pdf")


@login_required
def recording_print(request: HttpRequest, pk) -> HttpResponse:
    recording = get_recording_for_user(request, pk)
    report = content.recording_content(recording)
    return render(
        request, "reports/recording_print.html", {"report": report, "recording": recording}
    )


def period(request: HttpRequest):
    return content.parse_day(request.GET.get("since")), content.parse_day(request.GET.get("until"))


@login_required
def progress_page(request: HttpRequest, pk) -> HttpResponse:
    patient = get_patient_for_user(request, pk)
    if request.user.is_patient:  # their own progress page, in their words
        return redirect("dashboard:my-progress")
    prescribed = list(patient.prescriptions.select_related("exercise"))
    prescriptions = [
        {
            "exercise": p.exercise.name,
            "sessions_per_week": p.sessions_per_week,
            "target_repetitions": p.target_repetitions,
            "start": p.start_date.isoformat(),
            "end": p.end_date.isoformat() if p.end_date else None,
        }
        for p in prescribed
    ]
    adherence, days = patient_adherence(patient, prescriptions=prescribed)
    context = {
        "patient": patient,
        "prescriptions": prescriptions,
        "adherence": adherence,
        "days_with_data": days,
        "goal_lines": chart_lines(patient),
    }
    return render(request, "reports/progress.html", context)


@login_required
def progress_pdf(request: HttpRequest, pk) -> HttpResponse:
    patient = get_patient_for_user(request, pk)
    since, until = period(request)
    name = services.progress_report_name(patient, since, until)
    if not services.request_report("progress", patient.pk, name, since, until):
        return pending(request)
    return pdf_response(name, f"progress-{patient.pk}.pdf")


@login_required
def progress_print(request: HttpRequest, pk) -> HttpResponse:
    patient = get_patient_for_user(request, pk)
    report = content.progress_content(patient, *period(request))
    return render(request, "reports/progress_print.html", {"report": report, "patient": patient})
