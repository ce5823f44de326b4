"""A patient's history for other systems: CSV (one row per recording) and a FHIR R4 Bundle.

Both read each recording's newest succeeded run: its figures (score, repetitions and those passed)
from the run's reading (`webapp.recordings.reading`), its angles from `AnalysisRun.result`;
recordings without one are left out, runs without clinical angles (older runs) have empty
cells / no angle Observations. Access as every API view: another clinic's
patient, or another patient's record, answers 404; each export is written to the audit log.

FHIR: a ``collection`` Bundle with the Patient and, per recording, one Observation for the
session score (with its repetitions as components) and one per measured angle range
(``valueRange`` in degrees, UCUM ``deg``). No LOINC code for these measures was confirmed, so
they use the local code system `LOCAL_SYSTEM` (codes: ``session-score``, ``repetitions``,
``repetitions-passed``, ``span`` and the angle names of the interface contract, e.g.
``knee_flexion_left``), documented in docs/sections/clinical.md.
"""

from __future__ import annotations

import uuid
from typing import Any

from django.conf import settings
from django.http import HttpResponse
from django.utils import timezone
from drf_spectacular.types import OpenApiTypes
from drf_spectacular.utils import OpenApiResponse, extend_schema
from rest_framework.renderers import BaseRenderer, JSONRenderer
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from analysis.clinical import ANGLE_NAMES
from analysis.pipeline.results import AnalysisSummary
from webapp.accounts.permissions import get_patient_for_user
from webapp.api.fhir_schema import FhirBundleSerializer
from webapp.audit import log
from webapp.patients.history_export import (
    analysed_recordings,
    exercise_name,
    history_csv_response,
)
from webapp.patients.models import Patient
from webapp.recordings.models import Recording, RunReading

LOCAL_SYSTEM = getattr(settings, "FHIR_LOCAL_CODE_SYSTEM", "urn:physio-dashboard:measure")
UCUM = "http://unitsofmeasure.org"
CATEGORY = {
    "coding": [
        {
            "system": "http://terminology.hl7.org/CodeSystem/observation-category",
            "code": "exam",
            "display": "Exam",
        }
    ]
}


class CSVRenderer(BaseRenderer):
    """Lets clients ask for ``text/csv``; error answers are then plain text."""

    media_type = "text/csv"
    format = "csv"
    charset = "utf-8"

    def render(self, data, accepted_media_type=None, renderer_context=None):
        if isinstance(data, dict) and "detail" in data:
            return str(data["detail"]).encode()
        return str(data).encode()


def audited_patient(request: Request, pk) -> Patient:
    patient = get_patient_for_user(request, pk, audit=False)
    log.record(request, "export", patient, patient_id=patient.pk)
    return patient


class PatientHistoryCSV(APIView):
    """One row per analysed recording (`webapp.patients.history_export`): date, exercise, score,
    repetitions, repetitions passed, pain, each clinical angle's range in degrees (empty when the
    run did not measure it) and a note; units in the column names."""

    renderer_classes = [JSONRenderer, CSVRenderer]

    @extend_schema(responses={(200, "text/csv"): OpenApiResponse(OpenApiTypes.STR)})
    def get(self, request: Request, pk) -> HttpResponse:
        patient = get_patient_for_user(request, pk, audit=False)  # the export is the event
        return history_csv_response(request, patient)


def local_code(code: str, display: str) -> dict[str, Any]:
    return {"coding": [{"system": LOCAL_SYSTEM, "code": code, "display": display}], "text": display}


def quantity(value: float, unit: str, code: str) -> dict[str, Any]:
    return {"value": value, "unit": unit, "system": UCUM, "code": code}


def entry(resource: dict[str, Any]) -> dict[str, Any]:
    return {"fullUrl": f"urn:uuid:{resource['id']}", "resource": resource}


def patient_resource(patient: Patient) -> dict[str, Any]:
    resource: dict[str, Any] = {
        "resourceType": "Patient",
        "id": str(patient.pk),
        "active": patient.archived_at is None,
        "name": [{"text": patient.display_name}],
    }
    if patient.date_of_birth:
        resource["birthDate"] = patient.date_of_birth.isoformat()
    return resource


def observation(patient: Patient, recording: Recording, key: str, **fields) -> dict[str, Any]:
    """An Observation of one recording; its id is stable for (recording, key)."""
    return {
        "resourceType": "Observation",
        "id": str(uuid.uuid5(recording.pk, key)),
        "status": "final",
        "category": [CATEGORY],
        "subject": {"reference": f"urn:uuid:{patient.pk}"},
        "effectiveDateTime": recording.uploaded_at.isoformat(),
        **fields,
    }


def score_observation(patient: Patient, recording: Recording, reading: RunReading):
    """The session score with its repetitions and those passed as components: the run's reading
    (the therapist's verdicts first), the figures of every page and of the history CSV."""
    components = [
        {
            "code": local_code("repetitions", "Repetitions"),
            "valueQuantity": quantity(reading.repetition_count, "repetitions", "1"),
        },
        {
            "code": local_code("repetitions-passed", "Repetitions passed"),
            "valueQuantity": quantity(reading.passed_count, "repetitions", "1"),
        },
    ]
    name = exercise_name(recording) or "exercise"
    if not reading.fits or reading.score is None:  # not the exercise: no score, and why
        value: dict[str, Any] = {"dataAbsentReason": {"text": reading.statements["message"]}}
    else:
        value = {"valueQuantity": quantity(round(reading.score, 2), "score", "{score}")}
    return observation(
        patient,
        recording,
        "session-score",
        code=local_code("session-score", f"Exercise session score ({name}), 0-100"),
        component=components,
        **value,
    )


def angle_observations(patient: Patient, recording: Recording, result: AnalysisSummary):
    for name in ANGLE_NAMES:
        if name not in result.clinical_angles:
            continue
        span = result.clinical_angles[name]
        yield observation(
            patient,
            recording,
            name,
            code=local_code(name, f"{name.replace('_', ' ').capitalize()}, range of motion"),
            valueRange={
                "low": quantity(span.min, "deg", "deg"),
                "high": quantity(span.max, "deg", "deg"),
            },
            component=[
                {
                    "code": local_code("span", "Range (max - min)"),
                    "valueQuantity": quantity(span.range, "deg", "deg"),
                }
            ],
        )


def patient_bundle(patient: Patient) -> dict[str, Any]:
    """The FHIR R4 Bundle (type collection) of one patient's analysed history."""
    entries = [entry(patient_resource(patient))]
    for recording, result, reading in analysed_recordings(patient):
        entries.append(entry(score_observation(patient, recording, reading)))
        entries.extend(entry(o) for o in angle_observations(patient, recording, result))
    return {
        "resourceType": "Bundle",
        "id": str(uuid.uuid4()),
        "type": "collection",
        "timestamp": timezone.now().isoformat(),
        "entry": entries,
    }


class PatientFHIR(APIView):
    """The patient and their session scores and angle ranges as a FHIR R4 Bundle (JSON)."""

    @extend_schema(responses={(200, "application/fhir+json"): FhirBundleSerializer})
    def get(self, request: Request, pk) -> Response:
        patient = audited_patient(request, pk)
        return Response(patient_bundle(patient), content_type="application/fhir+json")
