"""Patients and what is prescribed to them."""

from __future__ import annotations

import uuid

from django.conf import settings
from django.db import models

from webapp.accounts.models import Clinic


class Patient(models.Model):
    """A person under treatment.

    Ids are random so that URLs shared outside the app reveal nothing.
    """

    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    clinic = models.ForeignKey(Clinic, on_delete=models.PROTECT, related_name="patients")
    user = models.OneToOneField(
        settings.AUTH_USER_MODEL,
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="patient_profile",
    )
    display_name = models.CharField(max_length=200)
    date_of_birth = models.DateField(null=True, blank=True)
    notes = models.TextField(blank=True)
    therapists = models.ManyToManyField(
        settings.AUTH_USER_MODEL, blank=True, related_name="assigned_patients"
    )
    created_at = models.DateTimeField(auto_now_add=True)
    archived_at = models.DateTimeField(null=True, blank=True)
    last_activity_at = models.DateTimeField(null=True, blank=True, db_index=True)

    class Meta:
        ordering = ["display_name"]
        indexes = [models.Index(fields=["clinic", "display_name"])]

    def __str__(self) -> str:
        return self.display_name


class Prescription(models.Model):
    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    patient = models.ForeignKey(Patient, on_delete=models.CASCADE, related_name="prescriptions")
    exercise = models.ForeignKey(
        "exercises.Exercise", on_delete=models.PROTECT, related_name="prescriptions"
    )
    sessions_per_week = models.PositiveSmallIntegerField(default=3)
    target_repetitions = models.PositiveSmallIntegerField(default=10)
    start_date = models.DateField()
    end_date = models.DateField(null=True, blank=True)
    notes = models.TextField(blank=True)
    created_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        ordering = ["-start_date"]


class PerformanceLevel(models.Model):
    """Current performance level γ of one patient for one joint of one exercise (0..1)."""

    patient = models.ForeignKey(Patient, on_delete=models.CASCADE, related_name="levels")
    exercise = models.ForeignKey("exercises.Exercise", on_delete=models.CASCADE)
    joint = models.CharField(max_length=100)
    gamma = models.FloatField()
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        constraints = [
            models.UniqueConstraint(
                fields=["patient", "exercise", "joint"], name="one_level_per_joint"
            )
        ]
