"""Progression of one patient: every succeeded run's headline figures, oldest first.

Used by the progress JSON endpoint, the charts and the REST API, so it runs one query and reads
only the summary keys it needs: the database extracts score, γ, range of motion and the number of
repetitions from each summary, and the rest of it (assessment, feedback: most of its 10–20 kB)
never reaches Python. With hundreds of runs per patient that is most of the endpoint's time.
"""

from __future__ import annotations

from typing import Any

from django.db.models import Func, IntegerField
from django.db.models.fields.json import KeyTransform

from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun, RunStatus


class JsonArrayLength(Func):
    """Length of a JSON array (NULL when the key is missing)."""

    function = "JSON_ARRAY_LENGTH"
    output_field = IntegerField()

    def as_postgresql(self, compiler, connection, **extra_context):
        return self.as_sql(compiler, connection, function="JSONB_ARRAY_LENGTH", **extra_context)


POINT_VALUES = {
    "repetition_count": JsonArrayLength(KeyTransform("repetitions", "summary")),
    "range_of_motion": KeyTransform("range_of_motion", "summary"),
    "gamma": KeyTransform("gamma", "summary"),
}
POINT_FIELDS = (
    "pk",
    "score",  # the run's score column, a copy of the summary's score
    "recording_id",
    "recording__exercise_id",
    "recording__exercise__name",
    "recording__uploaded_at",
    "recording__pain_score",
)


def run_point(row: dict[str, Any]) -> dict[str, Any]:
    exercise = row["recording__exercise_id"]
    return {
        "run": str(row["pk"]),
        "recording": str(row["recording_id"]),
        "exercise": str(exercise) if exercise else None,
        "exercise_name": row["recording__exercise__name"] if exercise else None,
        "date": row["recording__uploaded_at"].isoformat(),
        "score": row["score"],
        "repetitions": row["repetition_count"] or 0,
        "range_of_motion": row["range_of_motion"] or {},
        "gamma": row["gamma"] or {},
        "pain_score": row["recording__pain_score"],
    }


def patient_progress(
    patient: Patient, exercise_id: str | None = None, since=None, until=None
) -> list[dict[str, Any]]:
    runs = AnalysisRun.objects.filter(
        recording__patient=patient, status=RunStatus.SUCCEEDED
    ).order_by("recording__uploaded_at", "created_at")
    if exercise_id:
        runs = runs.filter(recording__exercise_id=exercise_id)
    if since:
        runs = runs.filter(recording__uploaded_at__date__gte=since)
    if until:
        runs = runs.filter(recording__uploaded_at__date__lte=until)
    latest: dict[Any, dict[str, Any]] = {}
    for row in runs.values(*POINT_FIELDS, **POINT_VALUES):
        latest[row["recording_id"]] = row  # a re-analysed recording counts once, by its newest run
    return [run_point(row) for row in latest.values()]
