from __future__ import annotations

from django.utils.dateparse import parse_date
from drf_spectacular.utils import OpenApiParameter, extend_schema
from rest_framework import generics, status
from rest_framework.exceptions import ValidationError
from rest_framework.parsers import FormParser, MultiPartParser
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from webapp.accounts.permissions import (
    get_patient_for_user,
    get_recording_for_user,
    visible_exercises,
    visible_patients,
)
from webapp.api.serializers import (
    ExerciseSerializer,
    PatientSerializer,
    RecordingSerializer,
    RecordingUploadSerializer,
)
from webapp.patients.progress import patient_progress
from webapp.recordings.forms import UploadForm
from webapp.recordings.uploads import store_recording

DATE_FILTERS = [
    OpenApiParameter("since", str, description="ISO date: only on or after this day"),
    OpenApiParameter("until", str, description="ISO date: only on or before this day"),
]


def date_param(request: Request, name: str):
    raw = request.query_params.get(name)
    if not raw:
        return None
    value = parse_date(raw)
    if value is None:
        raise ValidationError({name: f"'{raw}' is not a date (use YYYY-MM-DD)."})
    return value


class PatientList(generics.ListAPIView):
    serializer_class = PatientSerializer

    def get_queryset(self):
        return visible_patients(self.request.user).order_by("display_name")


class PatientDetail(generics.RetrieveAPIView):
    serializer_class = PatientSerializer

    def get_object(self):
        return get_patient_for_user(self.request, self.kwargs["pk"])


class PatientRecordings(generics.ListAPIView):
    serializer_class = RecordingSerializer

    @extend_schema(parameters=DATE_FILTERS)
    def get(self, request, *args, **kwargs):
        return super().get(request, *args, **kwargs)

    def get_queryset(self):
        patient = get_patient_for_user(self.request, self.kwargs["pk"])
        recordings = patient.recordings.prefetch_related("runs").order_by("-uploaded_at")
        since, until = date_param(self.request, "since"), date_param(self.request, "until")
        if since:
            recordings = recordings.filter(uploaded_at__date__gte=since)
        if until:
            recordings = recordings.filter(uploaded_at__date__lte=until)
        return recordings


class PatientProgress(APIView):
    @extend_schema(parameters=DATE_FILTERS, responses={200: dict})
    def get(self, request: Request, pk) -> Response:
        patient = get_patient_for_user(request, pk)
        points = patient_progress(
            patient,
            exercise_id=request.query_params.get("exercise"),
            since=date_param(request, "since"),
            until=date_param(request, "until"),
        )
        return Response({"patient": str(patient.pk), "points": points})


class ExerciseList(generics.ListAPIView):
    serializer_class = ExerciseSerializer

    def get_queryset(self):
        return visible_exercises(self.request.user).filter(archived_at__isnull=True)


class RecordingCreate(APIView):
    parser_classes = [MultiPartParser, FormParser]

    @extend_schema(request=RecordingUploadSerializer, responses={201: RecordingSerializer})
    def post(self, request: Request) -> Response:
        RecordingUploadSerializer(data=request.data).is_valid(raise_exception=True)
        get_patient_for_user(request, request.data.get("patient"))
        form = UploadForm(
            request.data, request.FILES,
            patients=visible_patients(request.user), exercises=visible_exercises(request.user),
        )
        if not form.is_valid():
            return Response(form.errors.get_json_data(), status=status.HTTP_400_BAD_REQUEST)
        data = form.cleaned_data
        recording, _ = store_recording(
            form.parsed, patient=data["patient"], exercise=data["exercise"], user=request.user,
            pain_score=data["pain_score"], note=data["note"],
        )
        body = RecordingSerializer(recording).data
        return Response(body, status=status.HTTP_201_CREATED)


class RecordingDetail(generics.RetrieveAPIView):
    serializer_class = RecordingSerializer

    def get_object(self):
        return get_recording_for_user(self.request, self.kwargs["pk"])
