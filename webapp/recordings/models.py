"""Recordings and analysis runs.

Run status transitions: QUEUED → RUNNING (claimed by one worker with a conditional UPDATE)
→ SUCCEEDED | FAILED. A run stuck in RUNNING past its time limit is reaped by the beat task.
Runs are immutable history: re-analysis makes a new run. A QUEUED run whose broker message was
lost (Redis restarted empty) is enqueued again by the beat task, a few times, then FAILED.

Every stored upload keeps its SHA-256 `checksum`; `webapp.recordings.storage.read_verified`
checks it on every read and marks the recording damaged on a mismatch.
"""

from __future__ import annotations

import uuid

from django.conf import settings
from django.db import models
from django.utils import timezone

from webapp.accounts.models import Clinic


class LiveRecordingManager(models.Manager):
    """The default manager hides the recordings of soft-deleted patients, like the patients."""

    def get_queryset(self):
        return super().get_queryset().filter(patient__deleted_at__isnull=True)


class Recording(models.Model):
    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    clinic = models.ForeignKey(Clinic, on_delete=models.PROTECT, related_name="recordings")
    patient = models.ForeignKey(
        "patients.Patient", on_delete=models.CASCADE, related_name="recordings"
    )
    exercise = models.ForeignKey(
        "exercises.Exercise",
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="recordings",
    )
    file = models.FileField(upload_to="recordings/%Y/%m/")
    original_name = models.CharField(max_length=255, blank=True)
    checksum = models.CharField(max_length=64, db_index=True)
    size_bytes = models.PositiveBigIntegerField(default=0)
    n_frames = models.PositiveIntegerField(default=0)
    n_joints = models.PositiveIntegerField(default=0)
    fps = models.FloatField(default=0.0)
    duration_s = models.FloatField(default=0.0)
    pain_score = models.PositiveSmallIntegerField(null=True, blank=True)
    note = models.TextField(blank=True)
    uploaded_by = models.ForeignKey(
        settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True, related_name="+"
    )
    uploaded_at = models.DateTimeField(auto_now_add=True, db_index=True)
    # Set when uploaded without an exercise: paper 002's guess, until someone confirms it.
    suggested_exercise = models.ForeignKey(
        "exercises.Exercise", on_delete=models.SET_NULL, null=True, blank=True, related_name="+"
    )
    suggestion_distance = models.FloatField(null=True, blank=True)
    # Set when the stored file no longer matches `checksum` (or is missing) on a read.
    damaged_at = models.DateTimeField(null=True, blank=True)
    damage = models.CharField(max_length=300, blank=True)

    objects = LiveRecordingManager()
    all_objects = models.Manager()

    class Meta:
        ordering = ["-uploaded_at"]
        indexes = [
            models.Index(fields=["patient", "exercise", "uploaded_at"]),
            # A patient's history, newest first, read page by page (patient page, API).
            models.Index(fields=["patient", "-uploaded_at"], name="recording_patient_newest"),
        ]


class RunStatus(models.TextChoices):
    QUEUED = "queued", "Queued"
    RUNNING = "running", "Running"
    SUCCEEDED = "succeeded", "Succeeded"
    FAILED = "failed", "Failed"


def summary_score(summary: dict | None) -> float | None:
    """The recording score (0–100) a run's summary holds, if any."""
    score = (summary or {}).get("score")
    return float(score) if isinstance(score, int | float) else None


class AnalysisRunQuerySet(models.QuerySet):
    """Keeps the `score` column equal to `summary["score"]` on bulk writes too."""

    def update(self, **fields):
        if "summary" in fields and "score" not in fields:
            fields["score"] = summary_score(fields["summary"])
        return super().update(**fields)

    def bulk_create(self, objs, *args, **kwargs):
        objs = list(objs)
        for run in objs:
            run.score = summary_score(run.summary)
        return super().bulk_create(objs, *args, **kwargs)


class AnalysisRun(models.Model):
    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    recording = models.ForeignKey(Recording, on_delete=models.CASCADE, related_name="runs")
    model = models.ForeignKey(
        "exercises.ExerciseModel", on_delete=models.SET_NULL, null=True, blank=True
    )
    code_version = models.CharField(max_length=40, blank=True)
    status = models.CharField(
        max_length=10, choices=RunStatus.choices, default=RunStatus.QUEUED, db_index=True
    )
    stage = models.CharField(max_length=60, blank=True)
    progress = models.PositiveSmallIntegerField(default=0)
    attempts = models.PositiveSmallIntegerField(default=0)
    worker = models.CharField(max_length=200, blank=True)
    # Who holds the run: a token per claim, so a worker that lost its lease cannot write results.
    lease_token = models.CharField(max_length=64, blank=True)
    heartbeat_at = models.DateTimeField(null=True, blank=True)
    created_at = models.DateTimeField(auto_now_add=True)
    # When its message was last handed to the broker, and how many times (see housekeeping).
    enqueued_at = models.DateTimeField(default=timezone.now)
    enqueue_count = models.PositiveSmallIntegerField(default=1)
    started_at = models.DateTimeField(null=True, blank=True)
    finished_at = models.DateTimeField(null=True, blank=True)
    user_error = models.TextField(blank=True)
    developer_error = models.TextField(blank=True)
    summary = models.JSONField(default=dict, blank=True)
    # A copy of summary["score"]: queries over many runs (score trends on the dashboard) read
    # this small column instead of every run's 10–20 kB summary.
    score = models.FloatField(null=True, blank=True)
    arrays = models.FileField(upload_to="runs/%Y/%m/", blank=True)

    objects = AnalysisRunQuerySet.as_manager()

    class Meta:
        ordering = ["-created_at"]
        indexes = [
            models.Index(fields=["recording", "-created_at"]),
            # Runs in one state by age (queued/running for the dashboard and the reaper, recent
            # failures): without it a large clinic scans every run.
            models.Index(fields=["status", "created_at"], name="run_status_created"),
        ]

    def save(self, *args, **kwargs):
        self.score = summary_score(self.summary)
        fields = kwargs.get("update_fields")
        if fields is not None and "summary" in fields:
            kwargs["update_fields"] = {*fields, "score"}
        super().save(*args, **kwargs)


class LandmarkCorrection(models.Model):
    """A therapist's corrected key poses for one run: training data for the next model."""

    run = models.ForeignKey(AnalysisRun, on_delete=models.CASCADE, related_name="landmark_fixes")
    frames = models.JSONField()
    types = models.JSONField()
    author = models.ForeignKey(settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True)
    created_at = models.DateTimeField(auto_now_add=True)
    used_in_model = models.ForeignKey(
        "exercises.ExerciseModel", on_delete=models.SET_NULL, null=True, blank=True
    )


class AssessmentCorrection(models.Model):
    """A therapist's corrected level for one joint at one key pose of a run."""

    run = models.ForeignKey(AnalysisRun, on_delete=models.CASCADE, related_name="assessment_fixes")
    frame = models.PositiveIntegerField()
    joint = models.CharField(max_length=100)
    level = models.PositiveSmallIntegerField()
    author = models.ForeignKey(settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True)
    created_at = models.DateTimeField(auto_now_add=True)
    used_in_model = models.ForeignKey(
        "exercises.ExerciseModel", on_delete=models.SET_NULL, null=True, blank=True
    )


class RepetitionLabel(models.Model):
    """A therapist's pass/fail verdict on one repetition of a run: data for the 001 threshold."""

    run = models.ForeignKey(AnalysisRun, on_delete=models.CASCADE, related_name="repetition_labels")
    index = models.PositiveIntegerField()  # position in the run's summary["repetitions"]
    passed = models.BooleanField()
    author = models.ForeignKey(settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True)
    created_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        constraints = [
            models.UniqueConstraint(fields=["run", "index"], name="one_label_per_repetition")
        ]
