"""Progression of one patient: every succeeded run's headline figures, oldest first.

Used by the progress JSON endpoint, the charts and the REST API, so it runs one query and reads
only the summary keys it needs: the database extracts score, γ, range of motion, the number of
repetitions, the clinical angle ranges and each hand's reachable area from each summary, and
the rest of it (assessment, feedback, the workspace hulls: most of its 10–20 kB) never reaches
Python. With hundreds of runs per patient that is most of the endpoint's time.
"""

from __future__ import annotations

from typing import Any

from django.db.models import Func, IntegerField
from django.db.models.fields.json import KeyTransform

from analysis.clinical.labels import REGIONS, angle_label, region_of
from analysis.pipeline.results import AngleRange
from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun, RunStatus


class JsonArrayLength(Func):
    """Length of a JSON array (NULL when the key is missing)."""

    function = "JSON_ARRAY_LENGTH"
    output_field = IntegerField()

    def as_postgresql(self, compiler, connection, **extra_context):
        return self.as_sql(compiler, connection, function="JSONB_ARRAY_LENGTH", **extra_context)


def workspace_area(side: str) -> KeyTransform:
    """summary.workspace.<side>.relative_area, without reading the hull."""
    return KeyTransform("relative_area", KeyTransform(side, KeyTransform("workspace", "summary")))


POINT_VALUES = {
    "repetition_count": JsonArrayLength(KeyTransform("repetitions", "summary")),
    "range_of_motion": KeyTransform("range_of_motion", "summary"),
    "gamma": KeyTransform("gamma", "summary"),
    "clinical_angles": KeyTransform("clinical_angles", "summary"),
    "workspace_left": workspace_area("left"),
    "workspace_right": workspace_area("right"),
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
        "clinical_angles": angle_ranges_of(row["clinical_angles"]),
        "workspace": {
            side: float(row[f"workspace_{side}"])
            for side in ("left", "right")
            if row[f"workspace_{side}"] is not None
        },
    }


def angle_ranges_of(stored: Any) -> dict[str, dict[str, float]]:
    """The summary's clinical_angles read through `AngleRange` (min, max, range in degrees)."""
    if not isinstance(stored, dict):
        return {}
    return {str(k): AngleRange.from_json(v).to_json() for k, v in stored.items()}


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


WORKSPACE_LABELS = {"left": "Left hand", "right": "Right hand"}
REGION_ORDER = {title: i for i, (title, _) in enumerate(REGIONS)}


def _exercise_series(points: list[dict[str, Any]]) -> dict[str, Any]:
    """One exercise's clinical series over its sessions (None where a session lacks a value)."""
    names = sorted(
        {n for p in points for n in p["clinical_angles"]},
        key=lambda n: (REGION_ORDER.get(region_of(n), len(REGION_ORDER)), n),
    )
    angles = [
        {
            "name": name,
            "label": angle_label(name),
            "region": region_of(name),
            "range": [p["clinical_angles"].get(name, {}).get("range") for p in points],
            "min": [p["clinical_angles"].get(name, {}).get("min") for p in points],
            "max": [p["clinical_angles"].get(name, {}).get("max") for p in points],
        }
        for name in names
    ]
    sides = sorted({s for p in points for s in p["workspace"]})
    workspace = [
        {
            "side": side,
            "label": WORKSPACE_LABELS.get(side, side),
            "percent": [_percent(p["workspace"].get(side)) for p in points],
        }
        for side in sides
    ]
    dates = [p["date"][:10] for p in points]
    return {"dates": dates, "angles": angles, "workspace": workspace}


def _percent(share: float | None) -> float | None:
    return None if share is None else round(100.0 * share, 1)


def clinical_progress(patient: Patient) -> list[dict[str, Any]]:
    """Per exercise (never mixing exercises in one series), each clinical angle's range in
    degrees and each hand's reachable area (% of the front hemisphere) over the session dates.
    One query (`patient_progress`); sessions without clinical measures are left out."""
    by_exercise: dict[str, list[dict[str, Any]]] = {}
    for point in patient_progress(patient):
        if point["clinical_angles"] or point["workspace"]:
            by_exercise.setdefault(point["exercise_name"] or "Unknown exercise", []).append(point)
    return [
        {"exercise": name, "id": f"clinical-{i}", **_exercise_series(points)}
        for i, (name, points) in enumerate(by_exercise.items())
    ]
