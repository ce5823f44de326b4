"""The stored progress points (`webapp.dashboard.models.ProgressPoint`): one per succeeded run.

A point holds what the progress charts and the API take from a run's summary (score, number of
repetitions, range of motion, γ, clinical angle ranges, each hand's reachable area), rendered once
as JSON text, plain and rounded. The database extracts those keys from the summary, so the rest
of it (assessment, feedback, workspace hulls: most of its 10–20 kB) never reaches Python; the
keys are the typed summary's field names (`POINT_PATHS`), checked when the module loads.

Written when a run succeeds (`store_after_run`), in bulk after a bulk load (`store_missing`), and
by a read that meets a succeeded run without one (`store_points`): a summary is written once, when
its run succeeds, so a stored point never goes stale; deleting the run deletes it.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import fields
from typing import Any

from django.db.models import Func, IntegerField, QuerySet
from django.db.models.fields.json import KeyTransform

from analysis.pipeline.results import AnalysisSummary, AngleRange, WorkspaceSummary
from webapp.api.numbers import rounded
from webapp.dashboard.models import ProgressPoint
from webapp.recordings.models import AnalysisRun, RunStatus


class JsonArrayLength(Func):
    """Length of a JSON array (NULL when the key is missing)."""

    function = "JSON_ARRAY_LENGTH"
    output_field = IntegerField()

    def as_postgresql(self, compiler, connection, **extra_context):
        return self.as_sql(compiler, connection, function="JSONB_ARRAY_LENGTH", **extra_context)


def typed_field(cls: type, name: str) -> str:
    """A field name of a typed result, checked when this module loads: a renamed field stops the
    start instead of leaving the charts empty."""
    if name not in {f.name for f in fields(cls)}:
        raise LookupError(f"{cls.__name__} has no field {name!r}")
    return name


SIDES = ("left", "right")
# Point value -> its path in the stored summary (`AnalysisSummary.to_json`).
POINT_PATHS: dict[str, tuple[str, ...]] = {
    "repetition_count": (typed_field(AnalysisSummary, "repetitions"),),  # the list's length
    "range_of_motion": (typed_field(AnalysisSummary, "range_of_motion"),),
    "gamma": (typed_field(AnalysisSummary, "gamma"),),
    "clinical_angles": (typed_field(AnalysisSummary, "clinical_angles"),),
    **{
        f"workspace_{side}": (
            typed_field(AnalysisSummary, "workspace"),
            side,
            typed_field(WorkspaceSummary, "relative_area"),
        )
        for side in SIDES
    },
}
COUNTED = {"repetition_count"}


def _in_database(name: str, path: tuple[str, ...]) -> Func | KeyTransform:
    expression = KeyTransform(path[0], "summary")
    for key in path[1:]:
        expression = KeyTransform(key, expression)
    return JsonArrayLength(expression) if name in COUNTED else expression


def _in_python(name: str, path: tuple[str, ...], summary: dict[str, Any]) -> Any:
    value: Any = summary
    for key in path:
        value = value.get(key) if isinstance(value, dict) else None
    if name in COUNTED:
        return len(value) if isinstance(value, list) else None
    return value


POINT_VALUES = {name: _in_database(name, path) for name, path in POINT_PATHS.items()}


def summary_values(summary: dict[str, Any]) -> dict[str, Any]:
    """What `POINT_VALUES` extracts, read from a summary already in Python (a bulk load that
    generates its summaries renders their points without reading them back)."""
    return {name: _in_python(name, path, summary) for name, path in POINT_PATHS.items()}


def angle_ranges_of(stored: Any) -> dict[str, dict[str, float]]:
    """The summary's clinical_angles read through `AngleRange` (min, max, range in degrees)."""
    if not isinstance(stored, dict):
        return {}
    return {str(k): AngleRange.from_json(v).to_json() for k, v in stored.items()}


def run_figures(row: dict[str, Any]) -> dict[str, Any]:
    """The part of a progress point that comes from the run's summary (`score`: the run's score
    column, a copy of the summary's)."""
    return {
        "score": row["score"],
        "repetitions": row["repetition_count"] or 0,
        "range_of_motion": row["range_of_motion"] or {},
        "gamma": row["gamma"] or {},
        "clinical_angles": angle_ranges_of(row["clinical_angles"]),
        "workspace": {
            side: float(row[f"workspace_{side}"])
            for side in SIDES
            if row[f"workspace_{side}"] is not None
        },
    }


def rendered(row: dict[str, Any]) -> ProgressPoint:
    figures = run_figures(row)
    return ProgressPoint(
        run_id=row["pk"],
        page=json.dumps(figures),
        api=json.dumps(rounded(figures)),
        joints=json.dumps(sorted({*figures["range_of_motion"], *figures["gamma"]})),
        clinical=bool(figures["clinical_angles"] or figures["workspace"]),
    )


def extracted(runs: QuerySet) -> QuerySet:
    """Rows with the summary keys a point needs, extracted by the database."""
    return runs.values("pk", "score", **POINT_VALUES)


def store_points(run_ids: Iterable[Any]) -> dict[Any, ProgressPoint]:
    """Render and store the points of these succeeded runs (two queries); keyed by run id."""
    runs = AnalysisRun.objects.filter(pk__in=list(run_ids), status=RunStatus.SUCCEEDED)
    points = {row["pk"]: rendered(row) for row in extracted(runs.order_by())}
    # A worker and a page may render the same run at once: the first write stands (same text).
    ProgressPoint.objects.bulk_create(points.values(), ignore_conflicts=True)
    return points


def store_after_run(run_id: Any) -> None:
    """The update on write, after a run ends (a failed run has no point)."""
    store_points([run_id])


def store_missing(
    runs: QuerySet, batch: int = 5000, report: Callable[[int, float], None] | None = None
) -> int:
    """Store the points every succeeded run in `runs` lacks (after a bulk load); returns how many.

    Reads in batches of run ids, so a million runs never sit in memory at once; `report(done,
    seconds)` after each batch shows the progress of a long backfill.
    """
    todo = runs.filter(status=RunStatus.SUCCEEDED, progress_point__isnull=True).order_by()
    started, done = time.perf_counter(), 0
    for ids in _batches(todo.values_list("pk", flat=True).iterator(chunk_size=batch), batch):
        rows = extracted(AnalysisRun.objects.filter(pk__in=ids).order_by())
        ProgressPoint.objects.bulk_create(
            [rendered(row) for row in rows], batch_size=1000, ignore_conflicts=True
        )
        done += len(ids)
        if report is not None:
            report(done, time.perf_counter() - started)
    return done


def _batches(values: Iterator[Any], size: int) -> Iterator[list[Any]]:
    chunk: list[Any] = []
    for value in values:
        chunk.append(value)
        if len(chunk) == size:
            yield chunk
            chunk = []
    if chunk:
        yield chunk
