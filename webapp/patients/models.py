"""Patients and what is prescribed to them."""

from __future__ import annotations

import uuid
from datetime import timedelta

from django.conf import settings
from django.core.validators import MaxValueValidator, MinValueValidator
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
    # Reminders of missed sessions (webapp.patients.reminders): off unless the therapist turns
    # them on; sent to `email`, or to the patient's account's address when it is empty.
    send_reminders = models.BooleanField(default=False)
    email = models.EmailField(blank=True)
    last_reminder_on = models.DateField(null=True, blank=True)

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


WEEKDAYS = ("mon", "tue", "wed", "thu", "fri", "sat", "sun")  # date.weekday() order
# Lowest and highest value of each part of a dosage (a session is a day: seven a week at most).
DOSAGE_LIMITS = {
    "sessions_per_week": (1, 7),
    "sets": (1, 20),
    "target_repetitions": (1, 200),
    "hold_seconds": (0, 600),
}


def dosage_field(
    low: int, high: int, default: int | None = None
) -> models.PositiveSmallIntegerField:
    validators = [MinValueValidator(low), MaxValueValidator(high)]
    return models.PositiveSmallIntegerField(
        null=True, blank=True, default=default, validators=validators
    )


class Prescription(models.Model):
    """An exercise prescribed to a patient, with its dosage (every part optional).

    A session is a day with at least one recording of the exercise (webapp.patients.adherence),
    so a week holds at most seven. `days` lists the weekdays the therapist suggests
    ("mon,wed,fri"); the prescription form and the API set `sessions_per_week` to their number
    when it is left empty.
    """

    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    patient = models.ForeignKey(Patient, on_delete=models.CASCADE, related_name="prescriptions")
    exercise = models.ForeignKey(
        "exercises.Exercise", on_delete=models.PROTECT, related_name="prescriptions"
    )
    sessions_per_week = dosage_field(*DOSAGE_LIMITS["sessions_per_week"], default=3)
    sets = dosage_field(*DOSAGE_LIMITS["sets"])
    # Per set; `repetitions` in the API (the column keeps its name for older backups).
    target_repetitions = dosage_field(*DOSAGE_LIMITS["target_repetitions"], default=10)
    hold_seconds = dosage_field(*DOSAGE_LIMITS["hold_seconds"])
    days = models.CharField(max_length=27, blank=True)
    start_date = models.DateField()
    end_date = models.DateField(null=True, blank=True)
    notes = models.TextField(blank=True)
    created_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        ordering = ["-start_date"]

    @property
    def weekdays(self) -> list[int]:
        """The suggested days as `date.weekday()` numbers (Monday 0)."""
        return [WEEKDAYS.index(d) for d in self.days.split(",") if d in WEEKDAYS]

    @property
    def dosage(self) -> str:
        """The dosage in words ("3 sets of 10 repetitions, 3 sessions a week")."""
        from webapp.patients.dosage import dosage_words

        return dosage_words(self)


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


class Goal(models.Model):
    """A target the therapist sets for one exercise of a patient, to reach by a date.

    `measure` is a clinical angle name (`analysis.clinical.ANGLE_NAMES`: the angle's range of
    motion in degrees), "score" (0–100) or "adherence" (% of prescribed sessions done over the
    last four weeks). `webapp.patients.goals` says how a goal is judged met, on or off track.
    """

    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    patient = models.ForeignKey(Patient, on_delete=models.CASCADE, related_name="goals")
    exercise = models.ForeignKey(
        "exercises.Exercise", on_delete=models.PROTECT, related_name="goals"
    )
    measure = models.CharField(max_length=60)
    target = models.FloatField()
    by = models.DateField()
    created_by = models.ForeignKey(
        settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True, related_name="+"
    )
    created_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        ordering = ["by", "created_at"]
