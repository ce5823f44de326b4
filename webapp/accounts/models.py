"""Clinics and users. Every clinical row belongs to exactly one clinic."""

from __future__ import annotations

from django.contrib.auth.models import AbstractUser
from django.db import models


class Clinic(models.Model):
    name = models.CharField(max_length=200, unique=True)
    created_at = models.DateTimeField(auto_now_add=True)

    def __str__(self) -> str:
        return self.name


class Role(models.TextChoices):
    THERAPIST = "therapist", "Therapist"
    PATIENT = "patient", "Patient"
    CLINIC_ADMIN = "clinic_admin", "Clinic admin"


class User(AbstractUser):
    """A person who logs in. Superusers may have no clinic; everyone else has one."""

    clinic = models.ForeignKey(
        Clinic, on_delete=models.PROTECT, null=True, blank=True, related_name="users"
    )
    role = models.CharField(max_length=20, choices=Role.choices, default=Role.THERAPIST)

    @property
    def is_staff_member(self) -> bool:
        """Therapists and clinic admins work for the clinic; patients do not."""
        return self.role in (Role.THERAPIST, Role.CLINIC_ADMIN)

    @property
    def is_patient(self) -> bool:
        return self.role == Role.PATIENT
