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
from typing import TYPE_CHECKING

from django.conf import settings
from django.core.validators import MaxValueValidator, MinValueValidator
from django.db import models
from django.utils import timezone

from webapp.accounts.models import Clinic

if TYPE_CHECKING:
    from analysis.pipeline.results import AnalysisSummary


class LiveRecordingManager(models.Manager):
    """The default manager hides deleted recordings and the recordings of soft-deleted patients,
    like the patients (`all_objects` sees every row: backups, the purge, restoring)."""

    def get_queryset(self):
        return (
            super().get_queryset().filter(deleted_at__isnull=True, patient__deleted_at__isnull=True)
        )


class RecognitionState(models.TextChoices):
    """Where the worker's recognition of an upload's exercise stands (NONE: never asked)."""

    NONE = "", "Not asked"
    QUEUED = "queued", "Queued"
    RUNNING = "running", "Running"
    DONE = "done", "Done"
    FAILED = "failed", "Failed"


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
    # How hard the session felt to the patient, on the Borg CR10 scale (0 = nothing, 10 = maximal).
    effort = models.PositiveSmallIntegerField(
        null=True, blank=True, validators=[MinValueValidator(0), MaxValueValidator(10)]
    )
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
    # Recognising the exercise of an upload without one runs in a worker (workers/recognition.py):
    # the upload answers at once and the recording page follows these two fields.
    recognition = models.CharField(
        max_length=8, choices=RecognitionState.choices, default=RecognitionState.NONE, blank=True
    )
    recognition_progress = models.PositiveSmallIntegerField(default=0)
    # Set when the stored file no longer matches `checksum` (or is missing) on a read.
    damaged_at = models.DateTimeField(null=True, blank=True)
    damage = models.CharField(max_length=300, blank=True)
    # Set when staff delete the recording (webapp.recordings.recovery): hidden from every page,
    # list, export and the API until a clinic admin restores it.
    deleted_at = models.DateTimeField(null=True, blank=True, db_index=True)
    deleted_by = models.ForeignKey(
        settings.AUTH_USER_MODEL,
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="+",
    )

    objects = LiveRecordingManager()
    all_objects = models.Manager()

    class Meta:
        ordering = ["-uploaded_at"]
        indexes = [
            models.Index(fields=["patient", "exercise", "uploaded_at"]),
            # A patient's history, newest first, read page by page (patient page, API).
            models.Index(fields=["patient", "-uploaded_at"], name="recording_patient_newest"),
        ]

    def latest_succeeded_run(self) -> AnalysisRun | None:
        """The newest SUCCEEDED run: the result the pages, reports, playback and corrections use.

        A run only succeeds once its arrays file is stored, so no condition on the file: readers
        of the arrays handle a missing one (as for the file-less runs of the scale generator).
        With `runs` prefetched (list pages) it reads them instead of querying.
        """
        if "runs" in getattr(self, "_prefetched_objects_cache", {}):
            succeeded = [r for r in self.runs.all() if r.status == RunStatus.SUCCEEDED]
            return max(succeeded, key=lambda r: r.created_at, default=None)
        return self.runs.filter(status=RunStatus.SUCCEEDED).order_by("-created_at").first()


class RunStatus(models.TextChoices):
    QUEUED = "queued", "Queued"
    RUNNING = "running", "Running"
    SUCCEEDED = "succeeded", "Succeeded"
    FAILED = "failed", "Failed"


def summary_score(summary: dict | None) -> float | None:
    """The recording score (0–100) a run's stored summary holds, if any (the `score` column's
    source, tolerant of malformed rows; readers use `AnalysisRun.result`)."""
    score = (summary or {}).get("score")
    return float(score) if isinstance(score, int | float) else None


class AnalysisRunQuerySet(models.QuerySet):
    """Keeps the `score` column equal to the summary's score on bulk writes too."""

    def update(self, **fields):
        if "summary" in fields and "score" not in fields:
            fields["score"] = summary_score(fields["summary"])
        if "summary" in fields:  # a new summary: its reading is built again when next read
            RunReading.objects.filter(run__in=self.values("pk")).delete()
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
    # The `analyse --json` object as stored (served as-is by the API); read it through `result`.
    summary = models.JSONField(default=dict, blank=True)
    # A copy of the summary's score: queries over many runs (score trends on the dashboard) read
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
        if not self._state.adding and (fields is None or "summary" in fields):
            drop_reading(self.pk)
        super().save(*args, **kwargs)

    @property
    def result(self) -> AnalysisSummary | None:
        """The stored summary as the pipeline's typed result, None while there is none.

        The one reader of `summary`: pages, API, reports and workers read attributes of this.
        Parsed once per instance, again only when `summary` is replaced (refresh, new value).
        """
        # Imported here: the numerical core loads when a result is read, not at Django start.
        from analysis.pipeline.results import AnalysisSummary

        if not self.summary:
            return None
        cached = self.__dict__.get("_result")
        if cached is None or cached[0] is not self.summary:
            cached = (self.summary, AnalysisSummary.from_json(self.summary))
            self.__dict__["_result"] = cached
        return cached[1]


def drop_reading(run_id) -> None:
    """Forget a run's reading (its summary or a correction changed): the next reader builds it
    again (`webapp.recordings.reading`); writers that know better build it at once."""
    RunReading.objects.filter(run_id=run_id).delete()


class ReadingSource(models.Model):
    """A row a run's reading is built from: writing or deleting one drops that reading."""

    class Meta:
        abstract = True

    def save(self, *args, **kwargs):
        super().save(*args, **kwargs)
        drop_reading(self.run_id)

    def delete(self, *args, **kwargs):
        drop_reading(self.run_id)
        return super().delete(*args, **kwargs)


class Correction(ReadingSource):
    """What every therapist correction of a run has: training data for the next model, marked
    with the model version that used it."""

    author = models.ForeignKey(settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True)
    created_at = models.DateTimeField(auto_now_add=True)
    used_in_model = models.ForeignKey(
        "exercises.ExerciseModel", on_delete=models.SET_NULL, null=True, blank=True
    )

    class Meta:
        abstract = True


class LandmarkCorrection(Correction):
    """A therapist's corrected key poses for one run."""

    run = models.ForeignKey(AnalysisRun, on_delete=models.CASCADE, related_name="landmark_fixes")
    frames = models.JSONField()
    types = models.JSONField()


class AssessmentCorrection(Correction):
    """A therapist's corrected level for one joint at one key pose of a run."""

    run = models.ForeignKey(AnalysisRun, on_delete=models.CASCADE, related_name="assessment_fixes")
    frame = models.PositiveIntegerField()
    joint = models.CharField(max_length=100)
    level = models.PositiveSmallIntegerField()


class RepetitionLabel(ReadingSource):
    """A therapist's pass/fail verdict on one repetition of a run: data for the 001 threshold."""

    run = models.ForeignKey(AnalysisRun, on_delete=models.CASCADE, related_name="repetition_labels")
    index = models.PositiveIntegerField()  # position in the run's `result.repetitions`
    passed = models.BooleanField()
    author = models.ForeignKey(settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True)
    created_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        constraints = [
            models.UniqueConstraint(fields=["run", "index"], name="one_label_per_repetition")
        ]


class RunReading(models.Model):
    """The one reading of a succeeded run: what every page, report, export and the API say of it.

    Built by `webapp.recordings.reading` from the run's result and the therapist's corrections
    (one verdict rule: the therapist's label first, then the analysis) when the run ends, when a
    therapist corrects it, and by the first reader that finds none. Lists read its figures.
    """

    run = models.OneToOneField(
        AnalysisRun, on_delete=models.CASCADE, primary_key=True, related_name="reading"
    )
    rule = models.PositiveSmallIntegerField(default=0)  # the building rule's version
    fits = models.BooleanField(default=True)  # False: the recording does not show the exercise
    score = models.FloatField(null=True, blank=True)
    repetition_count = models.PositiveIntegerField(default=0)
    passed_count = models.PositiveIntegerField(default=0)
    labelled_count = models.PositiveIntegerField(default=0)  # verdicts given by a therapist
    # [{"number", "score", "shown_score", "passed", "by", "verdict", "reasons"}, ...]
    repetitions = models.JSONField(default=list)
    # {"message", "to_correct", "went_well", "therapist"}: lists of sentences
    statements = models.JSONField(default=dict)
    built_at = models.DateTimeField(auto_now=True)

    def __str__(self) -> str:
        return f"reading of run {self.run_id}: {self.passed_count}/{self.repetition_count}"


class RecordingNote(models.Model):
    """A therapist's clinical note on one recording (shown on its page, in its PDF, in the API)."""

    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    recording = models.ForeignKey(Recording, on_delete=models.CASCADE, related_name="notes")
    author = models.ForeignKey(
        settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True, related_name="+"
    )
    text = models.TextField()
    created_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        ordering = ["created_at"]
