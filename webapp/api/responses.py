"""Typed OpenAPI descriptions of the API answers built as plain dicts (progress, prescriptions,
results-page data, corrections), and the normalisation those answers go through: datetimes as
ISO 8601 UTC with `Z`, numbers rounded (`webapp.api.numbers`). Keys the builders add later pass
through untouched; the serializers here describe them, they do not filter them."""

from __future__ import annotations

import json
from typing import Any

from django.http import HttpResponse, HttpResponseBase
from rest_framework import serializers
from rest_framework.request import Request
from rest_framework.response import Response

from analysis.pipeline.results import ExerciseMatch, RepetitionResult
from webapp.api.numbers import rounded, utc_iso
from webapp.api.serializers import (
    AngleRangeSerializer,
    AssessmentSerializer,
    LandmarkSerializer,
    UTCDateTimeField,
)


class ProgressPointSerializer(serializers.Serializer):
    run = serializers.UUIDField()
    recording = serializers.UUIDField()
    exercise = serializers.UUIDField(allow_null=True)
    exercise_name = serializers.CharField(allow_null=True)
    date = UTCDateTimeField()
    score = serializers.FloatField(allow_null=True)
    repetitions = serializers.IntegerField()
    range_of_motion = serializers.DictField(child=serializers.FloatField())
    gamma = serializers.DictField(child=serializers.FloatField())
    pain_score = serializers.IntegerField(allow_null=True)
    clinical_angles = serializers.DictField(child=AngleRangeSerializer())
    workspace = serializers.DictField(child=serializers.FloatField(), required=False)


class ProgressSerializer(serializers.Serializer):
    patient = serializers.UUIDField()
    points = ProgressPointSerializer(many=True)


def progress_response(request: Request, patient_id: Any, points_json: str) -> HttpResponseBase:
    """The progress answer around the points' JSON text (`progress_points_json(api=True)`:
    each point rounded, its date in UTC): sent as it is when JSON is asked for, as thousands of
    points would take longer to decode and encode again than the whole request otherwise."""
    body = f'{{"patient": "{patient_id}", "points": {points_json}}}'
    if request.accepted_renderer.format == "json":
        return HttpResponse(body, content_type="application/json")
    return Response(json.loads(body))  # the browsable API


class ResultRepetitionSerializer(serializers.Serializer):
    """A repetition as the result holds it (its keys generated from `RepetitionResult`) with the
    run's reading beside: the verdict (the therapist's label first), by whom, in words, why."""

    class Meta:
        result_class = RepetitionResult

    passed = serializers.BooleanField(
        help_text="the verdict: the therapist's label when they gave one, else the analysis'"
    )
    verdict_by = serializers.ChoiceField(choices=["therapist", "analysis"])
    verdict = serializers.CharField(help_text="the verdict in words, with the score it compares")
    reasons = serializers.ListField(
        child=serializers.CharField(), help_text="why, in words; never empty when not passed"
    )


class NamedAssessmentSerializer(AssessmentSerializer):
    type_name = serializers.CharField()


class CommentSerializer(serializers.Serializer):
    frame = serializers.IntegerField()
    text = serializers.CharField()
    tip = serializers.CharField(required=False)


class MatchSerializer(serializers.Serializer):
    """Whether the recording shows the exercise (keys generated from `ExerciseMatch`)."""

    class Meta:
        result_class = ExerciseMatch


class MetricsSerializer(serializers.Serializer):
    score = serializers.FloatField(allow_null=True, help_text="null when it does not fit")
    repetition_count = serializers.IntegerField()
    tempo = serializers.FloatField(allow_null=True)
    range_of_motion = serializers.DictField(child=serializers.FloatField())
    frames = serializers.IntegerField()
    fps = serializers.FloatField()
    mirrored = serializers.BooleanField()
    match = MatchSerializer()


class SimilarRecordingSerializer(serializers.Serializer):
    recording = serializers.UUIDField()
    patient = serializers.UUIDField()
    patient_name = serializers.CharField()
    uploaded_at = UTCDateTimeField()
    distance = serializers.FloatField()


class ReadingSerializer(serializers.Serializer):
    """The run's one reading (`webapp.recordings.reading`): what every page and export says."""

    fits = serializers.BooleanField(help_text="False: the recording does not show the exercise")
    score = serializers.FloatField(allow_null=True, help_text="0–100; null when it does not fit")
    repetition_count = serializers.IntegerField()
    passed_count = serializers.IntegerField(help_text="repetitions whose verdict is passed")
    labelled_count = serializers.IntegerField(help_text="verdicts given by a therapist")
    message = serializers.CharField(allow_blank=True, help_text="why it does not fit, or empty")
    to_correct = serializers.ListField(child=serializers.CharField())
    went_well = serializers.ListField(child=serializers.CharField())
    therapist = serializers.ListField(
        child=serializers.CharField(), help_text="the therapist's corrections, in words"
    )


class ResultDataSerializer(serializers.Serializer):
    """The results page's data; the analysis parts are there once the run succeeded."""

    recording = serializers.UUIDField()
    exercise = serializers.UUIDField(allow_null=True)
    run = serializers.UUIDField(allow_null=True)
    status = serializers.ChoiceField(
        choices=["queued", "running", "succeeded", "failed"], allow_null=True
    )
    model_version = serializers.IntegerField(required=False, allow_null=True)
    code_version = serializers.CharField(required=False)
    repetitions = ResultRepetitionSerializer(many=True, required=False)
    reading = ReadingSerializer(required=False, allow_null=True)
    pass_threshold = serializers.FloatField(required=False, allow_null=True)
    landmarks = LandmarkSerializer(many=True, required=False)
    assessment = NamedAssessmentSerializer(many=True, required=False)
    feedback = CommentSerializer(many=True, required=False)
    metrics = MetricsSerializer(required=False)
    gamma = serializers.DictField(child=serializers.FloatField(), required=False)
    similar = SimilarRecordingSerializer(many=True, required=False)


def result_body(data: dict[str, Any]) -> dict[str, Any]:
    body = rounded(data)
    if "similar" in body:
        body["similar"] = [{**s, "uploaded_at": utc_iso(s["uploaded_at"])} for s in body["similar"]]
    return body


class LandmarkFixSerializer(serializers.Serializer):
    frames = serializers.ListField(child=serializers.IntegerField())
    types = serializers.ListField(child=serializers.IntegerField())


class LevelFixSerializer(serializers.Serializer):
    frame = serializers.IntegerField()
    joint = serializers.CharField()
    level = serializers.IntegerField()


class VerdictSerializer(serializers.Serializer):
    index = serializers.IntegerField()
    passed = serializers.BooleanField()


class CorrectionsSerializer(serializers.Serializer):
    run = serializers.UUIDField(allow_null=True)
    landmarks = LandmarkFixSerializer(required=False, allow_null=True)
    levels = LevelFixSerializer(many=True, required=False)
    repetitions = VerdictSerializer(many=True, required=False)


class CorrectionsInputSerializer(serializers.Serializer):
    """What a therapist sends: any of the three (`webapp.recordings.corrections`)."""

    landmarks = LandmarkFixSerializer(required=False)
    levels = LevelFixSerializer(many=True, required=False)
    repetitions = VerdictSerializer(many=True, required=False)


class SavedCountsSerializer(serializers.Serializer):
    landmarks = serializers.IntegerField()
    levels = serializers.IntegerField()
    repetitions = serializers.IntegerField()


class CorrectionsSavedSerializer(CorrectionsSerializer):
    saved = SavedCountsSerializer()
