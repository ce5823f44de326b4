"""Progression of one patient: every succeeded run's headline figures, oldest first.

Used by the progress JSON endpoint, the charts and the REST API, so it reads only the summary
fields it needs and runs one query.
"""

from __future__ import annotations

from typing import Any

from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun, RunStatus


def run_point(run: AnalysisRun) -> dict[str, Any]:
    summary = run.summary or {}
    return {
        "run": str(run.pk),
        "recording": str(run.recording_id),
        "exercise": str(run.recording.exercise_id) if run.recording.exercise_id else None,
        "exercise_name": run.recording.exercise.name if run.recording.exercise_id else None,
        "date": run.recording.uploaded_at.isoformat(),
        "score": summary.get("score"),
        "repetitions": len(summary.get("repetitions", [])),
        "range_of_motion": summary.get("range_of_motion", {}),
        "gamma": summary.get("gamma", {}),
        "pain_score": run.recording.pain_score,
    }


def patient_progress(
    patient: Patient, exercise_id: str | None = None, since=None, until=None
) -> list[dict[str, Any]]:
    runs = (
        AnalysisRun.objects.filter(recording__patient=patient, status=RunStatus.SUCCEEDED)
        .select_related("recording__exercise")
        .order_by("recording__uploaded_at", "created_at")
    )
    if exercise_id:
        runs = runs.filter(recording__exercise_id=exercise_id)
    if since:
        runs = runs.filter(recording__uploaded_at__date__gte=since)
    if until:
        runs = runs.filter(recording__uploaded_at__date__lte=until)
    latest: dict[Any, AnalysisRun] = {}
    for run in runs:
        latest[run.recording_id] = run  # a re-analysed recording counts once, by its newest run
    return [run_point(run) for run in latest.values()]
