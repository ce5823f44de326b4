"""`GET|POST /api/v1/patients/{id}/prescriptions/`: a patient's prescriptions with their dosage
(`sets`, `repetitions`, `hold_seconds`, `sessions_per_week`, `days`) and adherence, and the
patient's days with data in the last 30 days (`webapp.patients.adherence` says how each is
counted). The clinic's staff prescribe; a patient reads their own."""

from __future__ import annotations

from typing import Any

from django.utils import timezone
from drf_spectacular.utils import extend_schema
from rest_framework import serializers, status
from rest_framework.exceptions import PermissionDenied
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from webapp.accounts.permissions import get_patient_for_user, visible_exercises
from webapp.patients.adherence import Adherence, patient_adherence
from webapp.patients.models import DOSAGE_LIMITS, WEEKDAYS, Prescription

# API name → model field (`repetitions` is stored as `target_repetitions`).
DOSAGE_FIELDS = {
    "sessions_per_week": "sessions_per_week",
    "sets": "sets",
    "repetitions": "target_repetitions",
    "hold_seconds": "hold_seconds",
}


def dosage_number(field: str, **kwargs: Any) -> serializers.IntegerField:
    low, high = DOSAGE_LIMITS[DOSAGE_FIELDS[field]]
    return serializers.IntegerField(min_value=low, max_value=high, allow_null=True, **kwargs)


class WeekSerializer(serializers.Serializer):
    first = serializers.DateField()
    last = serializers.DateField()
    sessions_prescribed = serializers.IntegerField()
    sessions_done = serializers.IntegerField()


class RecentAdherenceSerializer(serializers.Serializer):
    first = serializers.DateField()
    last = serializers.DateField()
    sessions_prescribed = serializers.IntegerField()
    sessions_done = serializers.IntegerField(help_text="each week counts at most its sessions")
    percent = serializers.FloatField(allow_null=True)
    weeks = WeekSerializer(many=True, help_text="four weeks of seven days, the last ends today")


class AdherenceSerializer(serializers.Serializer):
    prescription = serializers.CharField()
    exercise = serializers.CharField()
    exercise_name = serializers.CharField()
    sessions_prescribed = serializers.IntegerField(help_text="since the start")
    sessions_done = serializers.IntegerField(help_text="days with a recording, since the start")
    percent = serializers.FloatField(allow_null=True)
    last_4_weeks = RecentAdherenceSerializer()


class PrescriptionSerializer(serializers.Serializer):
    id = serializers.UUIDField()
    exercise = serializers.UUIDField()
    exercise_name = serializers.CharField()
    sessions_per_week = serializers.IntegerField(allow_null=True)
    sets = serializers.IntegerField(allow_null=True)
    repetitions = serializers.IntegerField(allow_null=True, help_text="per set")
    target_repetitions = serializers.IntegerField(allow_null=True, help_text="= repetitions")
    hold_seconds = serializers.IntegerField(allow_null=True)
    days = serializers.ListField(child=serializers.ChoiceField(choices=WEEKDAYS))
    start_date = serializers.DateField()
    end_date = serializers.DateField(allow_null=True)
    notes = serializers.CharField(allow_blank=True, help_text="instructions for the patient")
    adherence = AdherenceSerializer()


class DaysWithDataSerializer(serializers.Serializer):
    first = serializers.DateField()
    last = serializers.DateField()
    days = serializers.IntegerField(help_text="distinct days with at least one recording")
    window_days = serializers.IntegerField()


class PrescriptionsSerializer(serializers.Serializer):
    patient = serializers.UUIDField()
    days_with_data = DaysWithDataSerializer()
    prescriptions = PrescriptionSerializer(many=True)


class PrescriptionInputSerializer(serializers.Serializer):
    """A new prescription. Omitted numbers take their defaults (3 sessions a week, 10
    repetitions; without `sessions_per_week`, the number of `days` given)."""

    exercise = serializers.UUIDField()
    sessions_per_week = dosage_number("sessions_per_week", required=False)
    sets = dosage_number("sets", required=False)
    repetitions = dosage_number("repetitions", required=False, help_text="per set")
    hold_seconds = dosage_number("hold_seconds", required=False)
    days = serializers.ListField(
        child=serializers.ChoiceField(choices=WEEKDAYS), required=False, max_length=7
    )
    start_date = serializers.DateField(required=False, help_text="today when omitted")
    end_date = serializers.DateField(required=False, allow_null=True)
    notes = serializers.CharField(required=False, allow_blank=True, max_length=4000)

    def validate_days(self, days: list[str]) -> list[str]:
        if len(set(days)) != len(days):
            raise serializers.ValidationError("A day is listed twice.")
        return days

    def validate(self, data: dict[str, Any]) -> dict[str, Any]:
        start = data.setdefault("start_date", timezone.localdate())
        if data.get("end_date") and data["end_date"] < start:
            raise serializers.ValidationError({"end_date": "The end date is before the start."})
        if data.get("days") and data.get("sessions_per_week") is None:
            data["sessions_per_week"] = len(data["days"])
        return data


def prescription_row(prescription: Prescription, figures: Adherence) -> dict[str, Any]:
    dosage = {name: getattr(prescription, field) for name, field in DOSAGE_FIELDS.items()}
    return {
        "id": str(prescription.pk),
        "exercise": str(prescription.exercise_id),
        "exercise_name": prescription.exercise.name,
        **dosage,
        "target_repetitions": prescription.target_repetitions,
        "days": [WEEKDAYS[day] for day in prescription.weekdays],
        "start_date": prescription.start_date.isoformat(),
        "end_date": prescription.end_date.isoformat() if prescription.end_date else None,
        "notes": prescription.notes,
        "adherence": figures.to_json(),
    }


def create_prescription(request: Request, patient, data: dict[str, Any]) -> Prescription:
    exercises = visible_exercises(request.user).filter(archived_at__isnull=True)
    exercise = exercises.filter(pk=data.pop("exercise")).first()
    if exercise is None:
        raise serializers.ValidationError({"exercise": ["Unknown exercise."]})
    fields = {DOSAGE_FIELDS.get(name, name): value for name, value in data.items()}
    fields["days"] = ",".join(day for day in WEEKDAYS if day in set(data.get("days", [])))
    return Prescription.objects.create(patient=patient, exercise=exercise, **fields)


class PatientPrescriptions(APIView):
    """A patient's prescriptions with dosage and adherence; the clinic's staff add new ones."""

    @extend_schema(responses={200: PrescriptionsSerializer})
    def get(self, request: Request, pk) -> Response:
        patient = get_patient_for_user(request, pk)
        prescriptions = list(patient.prescriptions.select_related("exercise"))
        found, days = patient_adherence(patient, prescriptions=prescriptions)
        rows = [prescription_row(p, a) for p, a in zip(prescriptions, found, strict=True)]
        body = {"patient": str(patient.pk), "days_with_data": days.to_json(), "prescriptions": rows}
        return Response(body)

    @extend_schema(request=PrescriptionInputSerializer, responses={201: PrescriptionSerializer})
    def post(self, request: Request, pk) -> Response:
        patient = get_patient_for_user(request, pk)
        if not request.user.is_staff_member:
            raise PermissionDenied("Only the clinic's therapists prescribe.")
        data = PrescriptionInputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        prescription = create_prescription(request, patient, dict(data.validated_data))
        found, _ = patient_adherence(patient, prescriptions=[prescription])
        return Response(prescription_row(prescription, found[0]), status=status.HTTP_201_CREATED)
