"""The patient's own pages besides home: their progress per exercise and each prescribed
exercise's reference movement for the 3D view of today's plan.

Progress, one chart per exercise: the repetitions done well in each recent session, and each
range-of-motion goal's latest range against its target (goals: `webapp.patients.goals`).
"""

from __future__ import annotations

from collections import defaultdict
from typing import Any

from django.contrib.auth.decorators import login_required
from django.core.exceptions import PermissionDenied
from django.db.models import Prefetch
from django.http import Http404, HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import get_object_or_404, render
from django.views.decorators.http import require_GET

from webapp.accounts.permissions import visible_exercises, visible_patients
from webapp.exercises.annotate_data import tutor_pose
from webapp.patients.goals import ADHERENCE, SCORE, measure_label, patient_goal_statuses
from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun
from webapp.recordings.prescribed import prescribed_exercises
from webapp.recordings.reading import readings_of

SESSIONS_SHOWN = 10  # per exercise: the chart stays readable on a phone


def own_patient(request: HttpRequest) -> Patient:
    """The signed-in patient's record; every other role has no such page."""
    if not request.user.is_patient:
        raise PermissionDenied("These pages are the patient's own.")
    patient = visible_patients(request.user).first()
    if patient is None:
        raise Http404("No patient record is linked to this account.")
    return patient


def session_rows(patient: Patient) -> dict[str, list[dict[str, Any]]]:
    """Per exercise name, its analysed sessions oldest first: date, repetitions, done well (the
    runs' readings: one query for all, whatever the number of sessions)."""
    recordings = (
        patient.recordings.filter(exercise__isnull=False)
        .select_related("exercise")
        .prefetch_related(Prefetch("runs", queryset=AnalysisRun.objects.defer("summary")))
        .order_by("uploaded_at")
    )
    found: dict[str, list[dict[str, Any]]] = defaultdict(list)
    newest = {recording: recording.latest_succeeded_run() for recording in recordings}
    readings = readings_of(run.pk for run in newest.values() if run is not None)
    for recording, run in newest.items():
        reading = readings.get(run.pk) if run is not None else None
        if reading is None or not reading.fits:
            continue  # a recording that did not show the exercise has no repetitions to count
        found[recording.exercise.name].append(
            {
                "recording": recording,
                "done": reading.repetition_count,
                "well": reading.passed_count,
            }
        )
    return {name: rows[-SESSIONS_SHOWN:] for name, rows in found.items()}


def with_widths(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Each session's bar lengths in % of the longest session (the chart's scale)."""
    longest = max((row["done"] for row in rows), default=0) or 1
    return [
        {**row, "well_pct": 100 * row["well"] / longest, "done_pct": 100 * row["done"] / longest}
        for row in rows
    ]


def range_goals(patient: Patient) -> dict[str, list[dict[str, Any]]]:
    """Per exercise name, its range-of-motion goals: latest range, target, and both as % of the
    larger (a bar and its goal mark)."""
    found: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for status in patient_goal_statuses(patient):
        goal = status.goal
        if goal.measure in (SCORE, ADHERENCE):
            continue
        scale = max(goal.target, status.latest or 0.0) or 1.0
        found[goal.exercise.name].append(
            {
                "label": measure_label(goal.measure),
                "latest": status.latest,
                "target": goal.target,
                "by": goal.by,
                "state": status.state_words,
                "latest_pct": 100 * (status.latest or 0.0) / scale,
                "target_pct": 100 * goal.target / scale,
            }
        )
    return found


@login_required
@require_GET
def progress(request: HttpRequest) -> HttpResponse:
    patient = own_patient(request)
    sessions, goals = session_rows(patient), range_goals(patient)
    charts = [
        {"exercise": name, "sessions": with_widths(sessions.get(name, [])), "goals": goals[name]}
        for name in sorted(set(sessions) | set(goals))
    ]
    return render(request, "patients/patient_progress.html", {"patient": patient, "charts": charts})


@login_required
@require_GET
def reference(request: HttpRequest, pk) -> JsonResponse:
    """The reference movement of one exercise prescribed to the patient, for the 3D view."""
    patient = own_patient(request)
    exercise = get_object_or_404(
        prescribed_exercises(patient, visible_exercises(request.user)), pk=pk
    )
    if not exercise.tutor_ready():  # a reference video the worker has not read yet
        return JsonResponse({"detail": "The demonstration is not ready yet."}, status=409)
    motion = exercise.tutor_motion()
    return JsonResponse(
        {
            "fps": motion.fps,
            "frames": int(motion.frames.shape[0]),
            "names": list(motion.skeleton.names),
            **tutor_pose(motion),
        }
    )
