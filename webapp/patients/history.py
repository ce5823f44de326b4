"""Progress JSON for the charts and the CSV export of a patient's history."""

from __future__ import annotations

import csv
import json

from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.utils.dateparse import parse_date
from django.utils.text import slugify

from webapp.accounts.permissions import get_patient_for_user
from webapp.audit import log
from webapp.patients.progress import patient_progress, progress_points_json
from webapp.recordings.words import body_part

CSV_COLUMNS = ["date", "exercise_name", "score", "repetitions", "pain_score", "recording", "run"]


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
    patient = get_patient_for_user(request, pk, audit=False)
    log.record(request, "export", patient, patient_id=patient.pk)
    response = HttpResponse(content_type="text/csv; charset=utf-8")
    filename = f"history-{slugify(patient.display_name) or 'patient'}.csv"
    response["Content-Disposition"] = f'attachment; filename="{filename}"'
    writer = csv.writer(response)
    joints = sorted({j for p in patient_progress(patient) for j in p["range_of_motion"]})
    writer.writerow(CSV_COLUMNS + [f"rom_{j}" for j in joints] + [f"gamma_{j}" for j in joints])
    for point in patient_progress(patient):
        row = [point[c] for c in CSV_COLUMNS]
        row += [point["range_of_motion"].get(j, "") for j in joints]
        row += [point["gamma"].get(j, "") for j in joints]
        writer.writerow(row)
    return response
