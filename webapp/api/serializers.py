from __future__ import annotations

from rest_framework import serializers

from webapp.exercises.models import Exercise
from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun, Recording


class PatientSerializer(serializers.ModelSerializer):
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


class ExerciseSerializer(serializers.ModelSerializer):
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


class RunSerializer(serializers.ModelSerializer):
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


class RecordingSerializer(serializers.ModelSerializer):
    status = serializers.SerializerMethodField()
    progress = serializers.SerializerMethodField()
    result = serializers.SerializerMethodField()
    run = serializers.SerializerMethodField()

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
        ]

    def latest_run(self, recording: Recording) -> AnalysisRun | None:
        runs = list(recording.runs.all())
        return runs[0] if runs else None

    def get_status(self, recording: Recording) -> str | None:
        run = self.latest_run(recording)
        return run.status if run else None

    def get_progress(self, recording: Recording) -> int:
        run = self.latest_run(recording)
        return run.progress if run else 0

    def get_result(self, recording: Recording) -> dict | None:
        run = self.latest_run(recording)
        return run.summary if run and run.status == "succeeded" else None

    def get_run(self, recording: Recording) -> dict | None:
        run = self.latest_run(recording)
        return RunSerializer(run).data if run else None


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
