from __future__ import annotations

from django.core.exceptions import ValidationError as DjangoValidationError
from django.http import Http404
from django.utils.dateparse import parse_date
from drf_spectacular.types import OpenApiTypes
from drf_spectacular.utils import OpenApiParameter, PolymorphicProxySerializer, extend_schema
from rest_framework import generics, status
from rest_framework.exceptions import PermissionDenied, ValidationError
from rest_framework.parsers import MultiPartParser
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from analysis.bvh import read
from webapp.accounts.permissions import (
    get_exercise_for_user,
    get_patient_for_user,
    get_recording_for_user,
    visible_exercises,
    visible_patients,
)
from webapp.api import responses
from webapp.api.serializers import (
    ConfirmSerializer,
    ExerciseSerializer,
    PatientSerializer,
    RecordingMoveSerializer,
    RecordingSerializer,
    RecordingSummarySerializer,
    RecordingSummaryWithResultSerializer,
    RecordingUploadSerializer,
)
from webapp.api.summaries import recording_summaries
from webapp.patients.progress import progress_points_json
from webapp.recordings import recovery, services
from webapp.recordings.corrections import apply_corrections, corrections_of
from webapp.recordings.forms import MoveForm, UploadForm
from webapp.recordings.reading import readings_of, with_figures
from webapp.recordings.recovery import check_analysable
from webapp.recordings.results import result_data
from webapp.recordings.uploads import accept_upload, check_skeleton

DATE_FILTERS = [
    OpenApiParameter("since", OpenApiTypes.DATE, description="only on or after this day"),
    OpenApiParameter("until", OpenApiTypes.DATE, description="only on or before this day"),
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


FIELDS_PARAMETER = OpenApiParameter(
    "fields",
    OpenApiTypes.STR,
    enum=["result"],
    description="`result`: add each recording's full analysis result (large)",
)


class PatientRecordings(generics.ListAPIView):
    """A patient's recordings, newest first, as summaries (status, score, repetitions, passed,
    links); the full result is on the recording's endpoint or here with `?fields=result`."""

    def with_result(self) -> bool:
        fields = self.request.query_params.get("fields")
        if fields not in (None, "", "result"):
            raise ValidationError({"fields": f"'{fields}' is not a field set (use 'result')."})
        return fields == "result"

    def get_serializer_class(self):
        if self.with_result():
            return RecordingSummaryWithResultSerializer
        return RecordingSummarySerializer

    def paginate_queryset(self, queryset):
        """The page's rows, each with its newest run's reading figures (built once if missing);
        with `?fields=result`, each with the reading whose verdicts its result carries."""
        rows = with_figures(super().paginate_queryset(queryset))
        if self.with_result():
            found = readings_of(row.run_id for row in rows if row.run_status == "succeeded")
            for row in rows:
                row.run_reading = found.get(row.run_id)
        return rows

    @extend_schema(
        parameters=[*DATE_FILTERS, FIELDS_PARAMETER],
        # A summary, or with `?fields=result` a summary with its result: each closed, one fits.
        responses=PolymorphicProxySerializer(
            component_name="RecordingSummaryOrWithResult",
            serializers=[RecordingSummarySerializer, RecordingSummaryWithResultSerializer],
            resource_type_field_name=None,
            many=True,
        ),
    )
    def get(self, request, *args, **kwargs):
        return super().get(request, *args, **kwargs)

    def get_queryset(self):
        patient = get_patient_for_user(self.request, self.kwargs["pk"])
        recordings = recording_summaries(
            patient.recordings.order_by("-uploaded_at"), with_result=self.with_result()
        )
        since, until = date_param(self.request, "since"), date_param(self.request, "until")
        if since:
            recordings = recordings.filter(uploaded_at__date__gte=since)
        if until:
            recordings = recordings.filter(uploaded_at__date__lte=until)
        return recordings


class PatientProgress(APIView):
    @extend_schema(parameters=DATE_FILTERS, responses={200: responses.ProgressSerializer})
    def get(self, request: Request, pk) -> Response:
        patient = get_patient_for_user(request, pk)
        points, _ = progress_points_json(
            patient,
            exercise_id=request.query_params.get("exercise"),
            since=date_param(request, "since"),
            until=date_param(request, "until"),
            api=True,
        )
        return responses.progress_response(request, patient.pk, points)


class ExerciseList(generics.ListAPIView):
    serializer_class = ExerciseSerializer

    def get_queryset(self):
        return visible_exercises(self.request.user).filter(archived_at__isnull=True)


class RecordingCreate(APIView):
    # Multipart only: a url-encoded form cannot carry the file, so the schema must not offer it.
    parser_classes = [MultiPartParser]

    @extend_schema(request=RecordingUploadSerializer, responses={201: RecordingSerializer})
    def post(self, request: Request) -> Response:
        RecordingUploadSerializer(data=request.data).is_valid(raise_exception=True)
        get_patient_for_user(request, request.data.get("patient"))
        form = UploadForm(
            request.data,
            request.FILES,
            patients=visible_patients(request.user),
            exercises=visible_exercises(request.user),
        )
        if not form.is_valid():
            return Response(form.errors.get_json_data(), status=status.HTTP_400_BAD_REQUEST)
        # Without an exercise, a worker recognises it: GET shows `suggested_exercise` later.
        recording, _ = accept_upload(form.parsed, form.cleaned_data, request.user)
        body = RecordingSerializer(recording).data
        return Response(body, status=status.HTTP_201_CREATED)


MOVE_REFUSED = "Only the clinic's therapists move or delete recordings."


def staff_recording(request: Request, pk, refusal: str, audit: bool = True):
    """A recording the clinic's staff act on: another clinic's (or patient's) is 404 before a
    patient's own is refused (403, ``refusal``), so a stranger learns nothing of it."""
    recording = get_recording_for_user(request, pk, audit=audit and request.user.is_staff_member)
    if not request.user.is_staff_member:
        raise PermissionDenied(refusal)
    return recording


class RecordingDetail(generics.RetrieveAPIView):
    """A recording with its newest run; staff move it (PATCH) or delete it (DELETE, soft)."""

    serializer_class = RecordingSerializer

    def get_object(self):
        return get_recording_for_user(self.request, self.kwargs["pk"])

    @extend_schema(request=RecordingMoveSerializer, responses={200: RecordingSerializer})
    def patch(self, request: Request, pk) -> Response:
        recording = staff_recording(request, pk, MOVE_REFUSED, audit=False)  # the move is the event
        RecordingMoveSerializer(data=request.data).is_valid(raise_exception=True)
        form = MoveForm(request.data, recording=recording, user=request.user)
        if not form.is_valid():
            return Response(form.errors.get_json_data(), status=status.HTTP_400_BAD_REQUEST)
        recovery.move_recording(request, recording, form.changes)
        return Response(RecordingSerializer(recording).data)

    @extend_schema(request=None, responses={204: None})
    def delete(self, request: Request, pk) -> Response:
        recovery.delete_recording(request, staff_recording(request, pk, MOVE_REFUSED, audit=False))
        return Response(status=status.HTTP_204_NO_CONTENT)


class RecordingResult(APIView):
    """Results data: repetitions, assessment, feedback, metrics, γ, similar earlier recordings."""

    @extend_schema(responses={200: responses.ResultDataSerializer})
    def get(self, request: Request, pk) -> Response:
        recording = get_recording_for_user(request, pk)
        data = result_data(recording, recording.runs.first(), request.user)
        return Response(responses.result_body(data))


class RecordingConfirm(APIView):
    """Confirm the exercise of a recording uploaded without one; starts its analysis."""

    @extend_schema(request=ConfirmSerializer, responses={200: RecordingSerializer})
    def post(self, request: Request, pk) -> Response:
        recording = get_recording_for_user(request, pk)
        data = ConfirmSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        if recording.exercise_id is not None:
            raise ValidationError({"exercise": "This recording's exercise is already set."})
        try:
            exercise = get_exercise_for_user(request, data.validated_data["exercise"])
        except Http404 as error:
            raise ValidationError({"exercise": "Unknown exercise."}) from error
        with recording.file.open("rb") as handle:
            try:
                check_analysable(exercise)
                check_skeleton(read(handle.read()), exercise)
            except DjangoValidationError as error:
                raise ValidationError({"exercise": error.messages}) from error
        services.confirm_exercise(recording, exercise)
        recording.refresh_from_db()
        return Response(RecordingSerializer(recording).data)


class RecordingCorrections(APIView):
    """Therapist corrections (landmarks, per-joint levels, pass/fail per repetition) of the latest
    analysis; they become training data for the next model and the pass/fail threshold."""

    def latest(self, request: Request, pk):
        recording = staff_recording(request, pk, "Only the clinic's therapists correct analyses.")
        return recording.latest_succeeded_run()

    @extend_schema(responses={200: responses.CorrectionsSerializer})
    def get(self, request: Request, pk) -> Response:
        run = self.latest(request, pk)
        return Response(corrections_of(run) if run else {"run": None})

    @extend_schema(
        request=responses.CorrectionsInputSerializer,
        responses={200: responses.CorrectionsSavedSerializer},
    )
    def post(self, request: Request, pk) -> Response:
        run = self.latest(request, pk)
        if run is None:
            raise ValidationError({"detail": "The recording has no finished analysis."})
        try:
            saved = apply_corrections(run, request.data, request.user)
        except DjangoValidationError as error:
            raise ValidationError(error.message_dict) from error
        return Response({"saved": saved, **corrections_of(run)})
