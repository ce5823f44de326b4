"""The patient's history as one CSV: the single builder behind every "history CSV" link.

The patient page's link (`patients:history-csv`) and the API (`/api/v1/patients/{id}/history.csv`,
the interface contract: date, exercise, score, repetitions, passed, each clinical angle's range)
answer the
same file. One row per recording that has a succeeded run (its newest), oldest first; its figures
(score, repetitions, passed: the therapist's verdicts first) are the run's reading
(`webapp.recordings.reading`), as on every page. Columns
speak to a therapist opening the file in a spreadsheet: plain words, and every number carries its
unit in the column name, e.g. ``score (/100)``, ``pain (0-10)``, ``left knee flexion range (°)``.
A recording that does not show its exercise has an empty score and says why in ``note``.
"""

from __future__ import annotations

import csv
from collections.abc import Iterator
from typing import Any, TextIO

from django.http import HttpRequest, HttpResponse
from django.utils.text import slugify

from analysis.clinical import ANGLE_NAMES
from analysis.clinical.labels import angle_label
from analysis.pipeline.results import AnalysisSummary
from webapp.api.numbers import utc_iso
from webapp.audit import log
from webapp.patients.models import Patient
from webapp.recordings.models import Recording, RunReading
from webapp.recordings.reading import readings_of

LEADING_COLUMNS = [
    "date (UTC)",
    "exercise",
    "score (/100)",
    "repetitions (count)",
    "repetitions passed (count)",
    "pain (0-10)",
    "effort Borg CR10 (0-10)",
]
ANGLE_COLUMNS = [f"{angle_label(name).lower()} range (°)" for name in ANGLE_NAMES]
COLUMNS = [*LEADING_COLUMNS, *ANGLE_COLUMNS, "note"]
# A spreadsheet runs a cell that starts with one of these as a formula (names are typed by people).
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def analysed_recordings(patient: Patient) -> list[tuple[Recording, AnalysisSummary, RunReading]]:
    """Each recording with a succeeded run, that run's result and its reading, oldest first."""
    recordings = (
        Recording.objects.filter(patient=patient)
        .select_related("exercise")
        .prefetch_related("runs")
        .order_by("uploaded_at")
    )
    newest = [(recording, recording.latest_succeeded_run()) for recording in recordings]
    readings = readings_of(run.pk for _, run in newest if run is not None)
    return [
        (recording, run.result, readings[run.pk])
        for recording, run in newest
        if run is not None and run.result is not None and run.pk in readings
    ]


def exercise_name(recording: Recording) -> str:
    return recording.exercise.name if recording.exercise else ""


def spreadsheet_text(text: str) -> str:
    """Text a spreadsheet shows as typed, never evaluates (a leading quote disarms a formula)."""
    return f"'{text}" if text.startswith(FORMULA_STARTS) else text


def note_of(result: AnalysisSummary) -> str:
    if result.match.fits:
        return ""
    reason = result.match.message or "This recording does not look like the exercise."
    return f"No score: {reason}"


def history_row(recording: Recording, result: AnalysisSummary, reading: RunReading) -> list[Any]:
    """One recording's row: its figures are its run's reading's (the therapist's verdicts
    counted), its angles the result's."""
    angles = result.clinical_angles
    return [
        utc_iso(recording.uploaded_at),
        spreadsheet_text(exercise_name(recording)),
        round(reading.score, 2) if reading.fits and reading.score is not None else "",
        reading.repetition_count,
        reading.passed_count,
        "" if recording.pain_score is None else recording.pain_score,
        "" if recording.effort is None else recording.effort,
        *(round(angles[name].range, 2) if name in angles else "" for name in ANGLE_NAMES),
        spreadsheet_text(note_of(result)),
    ]


def history_rows(patient: Patient) -> Iterator[list[Any]]:
    yield COLUMNS
    for recording, result, reading in analysed_recordings(patient):
        yield history_row(recording, result, reading)


def write_history_csv(patient: Patient, out: TextIO) -> None:
    """The patient's history CSV, header first, written to `out`."""
    csv.writer(out).writerows(history_rows(patient))


def history_csv_response(request: HttpRequest, patient: Patient) -> HttpResponse:
    """The download every history link answers; the export is written to the audit log."""
    log.record(request, "export", patient, patient_id=patient.pk)
    response = HttpResponse(content_type="text/csv; charset=utf-8")
    filename = f"history-{slugify(patient.display_name) or 'patient'}.csv"
    response["Content-Disposition"] = f'attachment; filename="{filename}"'
    write_history_csv(patient, response)
    return response
