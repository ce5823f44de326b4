"""An exercise is defined by its tutor (reference) recording and its key poses."""

from __future__ import annotations

import uuid
from typing import TYPE_CHECKING

from django.db import models, transaction
from django.db.models import Max

from webapp.accounts.models import Clinic

if TYPE_CHECKING:
    from analysis.bvh import Motion


class Exercise(models.Model):
    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    clinic = models.ForeignKey(Clinic, on_delete=models.PROTECT, related_name="exercises")
    name = models.CharField(max_length=200)
    description = models.TextField(blank=True)
    tutor_file = models.FileField(upload_to="tutors/")
    tutor_checksum = models.CharField(max_length=64, blank=True)
    # Key poses of the tutor: frame numbers and landmark type ids, in time order.
    tutor_landmark_frames = models.JSONField(default=list, blank=True)
    tutor_landmark_types = models.JSONField(default=list, blank=True)
    # {"1": "start", "2": "end of range"}: names shown to therapists and used in feedback.
    landmark_type_names = models.JSONField(default=dict, blank=True)
    involved_joints = models.JSONField(default=list, blank=True)
    feedback_grammar = models.TextField(blank=True)
    active_model = models.ForeignKey(
        "exercises.ExerciseModel",
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="+",
    )
    # Paper 001's pass/fail score threshold, refitted by Celery beat from therapist labels.
    pass_threshold = models.FloatField(null=True, blank=True)
    threshold_report = models.JSONField(default=dict, blank=True)
    created_at = models.DateTimeField(auto_now_add=True)
    archived_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["name"]
        constraints = [
            models.UniqueConstraint(fields=["clinic", "name"], name="exercise_name_per_clinic")
        ]

    def __str__(self) -> str:
        return self.name

    def tutor_motion(self) -> Motion:
        """The parsed tutor recording (read from storage once per instance and tutor file).

        Raises what `analysis.bvh.read` and the storage raise (BVHError, OSError).
        """
        # Imported here: the numerical core loads when a tutor is read, not at Django start.
        from analysis.bvh import read

        cached = self.__dict__.get("_tutor_motion")
        if cached is None or cached[0] != self.tutor_file.name:
            with self.tutor_file.open("rb") as handle:
                cached = (self.tutor_file.name, read(handle.read()))
            self.__dict__["_tutor_motion"] = cached
        return cached[1]


class ModelStatus(models.TextChoices):
    QUEUED = "queued", "Queued"
    RUNNING = "running", "Building"
    READY = "ready", "Ready"
    FAILED = "failed", "Failed"


class ExerciseModelManager(models.Manager["ExerciseModel"]):
    def create_next_version(self, exercise: Exercise, **fields) -> ExerciseModel:
        """A new row numbered one above the exercise's latest version (1 for the first).

        Takes a lock on the exercise row, so two builds never get the same number.
        """
        with transaction.atomic():
            locked = Exercise.objects.select_for_update().get(pk=exercise.pk)
            latest = self.filter(exercise=locked).aggregate(v=Max("version"))["v"] or 0
            return self.create(exercise=locked, version=latest + 1, **fields)


class ExerciseModel(models.Model):
    """One built version of an exercise's model; the exercise names its active version."""

    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    exercise = models.ForeignKey(Exercise, on_delete=models.CASCADE, related_name="models")
    version = models.PositiveIntegerField()
    status = models.CharField(
        max_length=10, choices=ModelStatus.choices, default=ModelStatus.QUEUED
    )
    progress = models.PositiveSmallIntegerField(default=0)
    artefact = models.FileField(upload_to="models/", blank=True)
    training_report = models.JSONField(default=dict, blank=True)
    code_version = models.CharField(max_length=40, blank=True)
    error = models.TextField(blank=True)
    created_at = models.DateTimeField(auto_now_add=True)
    finished_at = models.DateTimeField(null=True, blank=True)

    objects = ExerciseModelManager()

    class Meta:
        ordering = ["-version"]
        constraints = [
            models.UniqueConstraint(fields=["exercise", "version"], name="one_model_version")
        ]
