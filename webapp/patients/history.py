"""Progress JSON for the charts and the patient page's link to the history CSV."""

from __future__ import annotations

import json

from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.utils.dateparse import parse_date

from webapp.accounts.permissions import get_patient_for_user
from webapp.patients.history_export import history_csv_response
from webapp.patients.progress import progress_points_json
from webapp.recordings.words import body_part


@login_required
def progress_json(request: HttpRequest, pk) -> HttpResponse:
    patient = get_patient_for_user(request, pk)
    try:
        since, until = date_arg(request, "since"), date_arg(request, "until")
    except ValueError as error:
        return JsonResponse({"detail": str(error)}, status=400)
    # The stored points' JSON text, joined as it is (thousands of points per patient at most).
    points, joints = progress_points_json(
        patient, exercise_id=request.GET.get("exercise") or None, since=since, until=until
    )
    labels = {joint: body_part(joint) for joint in sorted(joints)}  # the charts' legend words
    body = f'{{"patient": "{patient.pk}", "points": {points}, "labels": {json.dumps(labels)}}}'
    return HttpResponse(body, content_type="application/json")


def date_arg(request: HttpRequest, name: str):
    raw = request.GET.get(name)
    if not raw:
        return None
    value = parse_date(raw) if len(raw) == 10 else None
    if value is None:
        raise ValueError(f"{name}: '{raw}' is not a date (use YYYY-MM-DD).")
    return value


@login_required
def history_csv(request: HttpRequest, pk) -> HttpResponse:
    """The same file as the API's history.csv (`webapp.patients.history_export`)."""
    patient = get_patient_for_user(request, pk, audit=False)  # the export is the event
    return history_csv_response(request, patient)
