"""Report downloads through the REST API (token or session authentication)."""

from __future__ import annotations

from drf_spectacular.types import OpenApiTypes
from drf_spectacular.utils import OpenApiResponse, extend_schema, inline_serializer
from rest_framework import serializers
from rest_framework.decorators import api_view
from rest_framework.request import Request
from rest_framework.response import Response

from webapp.accounts.permissions import get_patient_for_user, get_recording_for_user
from webapp.reports import services
from webapp.reports.views import pdf_response, period

PENDING = {"status": "pending", "detail": "The report is being generated; try again shortly."}
REPORT_RESPONSES = {
    (200, "application/pdf"): OpenApiResponse(OpenApiTypes.BINARY, description="The PDF report."),
    202: OpenApiResponse(
        inline_serializer(
            "ReportPending",
            {"status": serializers.ChoiceField(["pending"]), "detail": serializers.CharField()},
        ),
        description="Being generated; ask again shortly.",
    ),
}


@extend_schema(responses=REPORT_RESPONSES)
@api_view(["GET"])
def recording_report(request: Request, pk):
    recording = get_recording_for_user(request, pk)
    name = services.recording_report_name(recording)
    if not services.request_report("recording", recording.pk, name):
        return Response(PENDING, status=202)
    return pdf_response(name, f"recording-{recording.pk}.pdf")


@extend_schema(responses=REPORT_RESPONSES)
@api_view(["GET"])
def progress_report(request: Request, pk):
    patient = get_patient_for_user(request, pk)
    since, until = period(request)
    name = services.progress_report_name(patient, since, until)
    if not services.request_report("progress", patient.pk, name, since, until):
        return Response(PENDING, status=202)
    return pdf_response(name, f"progress-{patient.pk}.pdf")
