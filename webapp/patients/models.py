"""Patients and what is prescribed to them."""

from __future__ import annotations

import uuid
from datetime import timedelta

from django.conf import settings
from django.db import models, transaction
from django.utils import timezone

from webapp.accounts.models import Clinic


class PatientQuerySet(models.QuerySet):
    def past_retention(self, now=None):
        """Soft-deleted patients whose retention period (PATIENT_RETENTION_DAYS) is over."""
        days = settings.PATIENT_RETENTION_DAYS
        cutoff = (now or timezone.now()) - timedelta(days=days)
        return self.filter(deleted_at__isnull=False, deleted_at__lte=cutoff)


class LivePatientQuerySet(PatientQuerySet):
    def delete(self):
        """Deleting patients only marks them; `purge_deleted_patients` removes them later.

        Their own logins are deactivated at once, so they cannot reach the hidden records.
        """
        from django.contrib.auth import get_user_model

        with transaction.atomic(using=self.db):
            user_ids = list(self.exclude(user=None).values_list("user_id", flat=True))
            count = self.update(deleted_at=timezone.now())
            get_user_model().objects.filter(pk__in=user_ids).update(is_active=False)
        return count, {self.model._meta.label: count}


class LivePatientManager(models.Manager):
    """The default manager: soft-deleted patients are invisible to every list, form and API."""

    def get_queryset(self) -> LivePatientQuerySet:
        live = LivePatientQuerySet(self.model, using=self._db)
        return live.filter(deleted_at__isnull=True)


class Patient(models.Model):
    """A person under treatment.

    Ids are random so that URLs shared outside the app reveal nothing.
    Deleting a patient is a soft delete: `deleted_at` is set, the default manager (`objects`)
    hides the row everywhere, and the purge (after PATIENT_RETENTION_DAYS) deletes it with its
    recordings and files. `all_objects` sees every row (backups, the purge).
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
    deleted_at = models.DateTimeField(null=True, blank=True, db_index=True)

    objects = LivePatientManager()
    all_objects = PatientQuerySet.as_manager()

    class Meta:
        ordering = ["display_name"]
        indexes = [models.Index(fields=["clinic", "display_name"])]

    def __str__(self) -> str:
        return self.display_name

    def delete(self, using=None, keep_parents=False):
        """Soft delete: hide the patient now, purge after the retention period."""
        result = type(self).objects.using(using or self._state.db).filter(pk=self.pk).delete()
        self.refresh_from_db(fields=["deleted_at"])
        return result

    def hard_delete(self):
        """Remove the row and, by cascade, its prescriptions, levels, recordings and runs."""
        return super().delete()


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
