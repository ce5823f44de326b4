"""What the API answers, every object typed for the OpenAPI schema.

Lists answer summaries (a recording's status, score, repetition and passed counts and links);
the full `analyse --json` result is on the recording's own endpoint (or behind `?fields=result`),
as the typed result's JSON (`AnalysisSummary.to_json`, at the pipeline's precision) under a schema
generated from the same dataclasses. Datetimes are ISO 8601 in UTC with `Z`; the other numbers
are rounded to what they mean (`webapp.api.numbers`).
"""

from __future__ import annotations

import datetime
from typing import Any

from django.db import models
from django.urls import reverse
from drf_spectacular.utils import extend_schema_field
from rest_framework import serializers

from analysis.pipeline import AnalysisSummary
from webapp.api.numbers import round_or_none, utc_iso
from webapp.api.result_schema import RESULT_FIELD
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun, Recording
from webapp.recordings.reading import reading_of, served_summary

RUN_STATES = ["queued", "running", "succeeded", "failed"]


def typed_json(summary: dict[str, Any]) -> dict[str, Any]:
    """A stored result as the API serves it: the typed result's JSON (`AnalysisSummary`), so
    every answer has the generated schema's shape whatever the run stored."""
    return AnalysisSummary.from_json(summary).to_json()


class UTCDateTimeField(serializers.DateTimeField):
    """ISO 8601 in UTC ending in `Z`, whole seconds: one format in every answer."""

    def to_representation(self, value: datetime.datetime | str | None) -> str | None:
        return utc_iso(value) if value else None


class RoundedFloatField(serializers.FloatField):
    def __init__(self, *, places: int = 1, **kwargs) -> None:
        self.places = places
        super().__init__(**kwargs)

    def to_representation(self, value) -> float | None:
        return round_or_none(value, self.places)


class ApiModelSerializer(serializers.ModelSerializer):
    serializer_field_mapping = {
        **serializers.ModelSerializer.serializer_field_mapping,
        models.DateTimeField: UTCDateTimeField,
    }


class PatientSerializer(ApiModelSerializer):
    class Meta:
        model = Patient
        fields = [
            "id",
            "display_name",
            "date_of_birth",
            "created_at",
            "archived_at",
            "last_activity_at",
        ]


class ExerciseSerializer(ApiModelSerializer):
    involved_joints = serializers.ListField(child=serializers.CharField(), read_only=True)
    landmark_type_names = serializers.DictField(child=serializers.CharField(), read_only=True)

    class Meta:
        model = Exercise
        fields = [
            "id",
            "name",
            "description",
            "involved_joints",
            "landmark_type_names",
            "created_at",
        ]


class RunSerializer(ApiModelSerializer):
    class Meta:
        model = AnalysisRun
        fields = [
            "id",
            "status",
            "stage",
            "progress",
            "created_at",
            "started_at",
            "finished_at",
            "user_error",
            "code_version",
        ]


# Parts of the result that other answers (progress, results-page data) describe; the result
# itself is generated from its dataclasses (`webapp.api.result_schema`).
class LandmarkSerializer(serializers.Serializer):
    frame = serializers.IntegerField()
    type = serializers.IntegerField()
    origin = serializers.CharField(required=False)


class GuidanceSerializer(serializers.Serializer):
    type = serializers.CharField()
    frames = serializers.ListField(child=serializers.IntegerField())


class AngleRangeSerializer(serializers.Serializer):
    min = serializers.FloatField()
    max = serializers.FloatField()
    range = serializers.FloatField()


class AssessmentSerializer(serializers.Serializer):
    frame = serializers.IntegerField()
    type = serializers.IntegerField()
    levels = serializers.DictField(child=serializers.IntegerField())


class RecordingLinksSerializer(serializers.Serializer):
    self = serializers.CharField(help_text="this recording (with the full result)")
    result = serializers.CharField(help_text="the results-page data")


def recording_links(recording_id) -> dict[str, str]:
    return {
        "self": reverse("api-recording", args=[recording_id]),
        "result": reverse("api-recording-result", args=[recording_id]),
    }


class RecordingSerializer(ApiModelSerializer):
    """A recording with its newest analysis: `status`, `progress` and, when it succeeded,
    `result` holding the fields of `analyse --json`."""

    status = serializers.SerializerMethodField()
    progress = serializers.SerializerMethodField()
    result = serializers.SerializerMethodField()
    run = serializers.SerializerMethodField()
    fps = RoundedFloatField(places=1, read_only=True)
    duration_s = RoundedFloatField(places=2, read_only=True)
    suggestion_distance = RoundedFloatField(places=3, read_only=True, allow_null=True)
    links = serializers.SerializerMethodField()

    class Meta:
        model = Recording
        fields = [
            "id",
            "patient",
            "exercise",
            "original_name",
            "checksum",
            "n_frames",
            "fps",
            "duration_s",
            "pain_score",
            "note",
            "uploaded_at",
            "status",
            "progress",
            "result",
            "run",
            "suggested_exercise",
            "suggestion_distance",
            "recognition",  # the worker's recognition of an upload without exercise
            "links",
        ]

    def latest_run(self, recording: Recording) -> AnalysisRun | None:
        runs = list(recording.runs.all())
        return runs[0] if runs else None

    @extend_schema_field(serializers.ChoiceField(choices=RUN_STATES, allow_null=True))
    def get_status(self, recording: Recording) -> str | None:
        run = self.latest_run(recording)
        return run.status if run else None

    def get_progress(self, recording: Recording) -> int:
        run = self.latest_run(recording)
        return run.progress if run else 0

    @extend_schema_field(RESULT_FIELD)
    def get_result(self, recording: Recording) -> dict | None:
        """The result with the reading's verdicts (a therapist's label is the verdict)."""
        run = self.latest_run(recording)
        if run is None or run.status != "succeeded":
            return None
        return served_summary(run, reading_of(run))

    @extend_schema_field(RunSerializer(allow_null=True))
    def get_run(self, recording: Recording) -> dict | None:
        run = self.latest_run(recording)
        return RunSerializer(run).data if run else None

    @extend_schema_field(RecordingLinksSerializer)
    def get_links(self, recording: Recording) -> dict[str, str]:
        return recording_links(recording.pk)


class RecordingSummarySerializer(serializers.Serializer):
    """One recording in a list: its newest analysis in figures, the full result behind `links`.

    Reads the annotations of `webapp.api.summaries.recording_summaries` (no summary JSON)."""

    id = serializers.UUIDField()
    exercise = serializers.UUIDField(source="exercise_id", allow_null=True)
    exercise_name = serializers.CharField(allow_null=True)
    original_name = serializers.CharField()
    uploaded_at = UTCDateTimeField()
    n_frames = serializers.IntegerField()
    fps = RoundedFloatField(places=1)
    duration_s = RoundedFloatField(places=2)
    pain_score = serializers.IntegerField(allow_null=True)
    run = serializers.UUIDField(source="run_id", allow_null=True)
    status = serializers.ChoiceField(source="run_status", choices=RUN_STATES, allow_null=True)
    progress = serializers.IntegerField(source="run_progress", allow_null=True)
    score = RoundedFloatField(source="run_score", places=1, allow_null=True)
    fits = serializers.BooleanField(
        source="run_fits",
        allow_null=True,
        help_text="false: the recording does not show the exercise (no score, no repetition)",
    )
    repetitions = serializers.IntegerField(source="run_repetitions", allow_null=True)
    passed = serializers.IntegerField(
        source="run_passed",
        allow_null=True,
        help_text="repetitions passed: the therapist's verdict first, then the analysis'",
    )
    links = serializers.SerializerMethodField()

    @extend_schema_field(RecordingLinksSerializer)
    def get_links(self, recording: Recording) -> dict[str, str]:
        return recording_links(recording.pk)

    def to_representation(self, instance):
        data = super().to_representation(instance)
        if data["status"] != "succeeded":  # figures only of a finished analysis
            data["repetitions"] = data["passed"] = data["fits"] = None
        return data


class RecordingSummaryWithResultSerializer(RecordingSummarySerializer):
    """`?fields=result`: the summary plus the newest succeeded result."""

    result = serializers.SerializerMethodField()

    @extend_schema_field(RESULT_FIELD)
    def get_result(self, recording: Recording) -> dict | None:
        """The result with the reading's verdicts, as on the recording's own endpoint."""
        summary = getattr(recording, "run_summary", None)
        if recording.run_status != "succeeded" or not summary:
            return None
        run = AnalysisRun(pk=recording.run_id, status=recording.run_status, summary=summary)
        return served_summary(run, getattr(recording, "run_reading", None))


class RecordingUploadSerializer(serializers.Serializer):
    patient = serializers.UUIDField()
    exercise = serializers.UUIDField(required=False, allow_null=True)
    file = serializers.FileField()
    pain_score = serializers.IntegerField(
        min_value=0, max_value=10, required=False, allow_null=True
    )
    note = serializers.CharField(required=False, allow_blank=True, max_length=2000)


class ConfirmSerializer(serializers.Serializer):
    exercise = serializers.UUIDField()


class RecordingMoveSerializer(serializers.Serializer):
    """What `PATCH /api/v1/recordings/{id}/` may change: the recording moves to another exercise
    and/or patient of the clinic, and a new analysis run is queued (earlier runs are kept)."""

    exercise = serializers.UUIDField(
        required=False, help_text="an exercise of the clinic whose key poses are marked"
    )
    patient = serializers.UUIDField(required=False, help_text="a patient of the clinic")
