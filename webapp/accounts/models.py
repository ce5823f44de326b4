"""Clinics and users. Every clinical row belongs to exactly one clinic."""

from __future__ import annotations

import uuid

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
    # How pages and the API name an account (the numeric key would be guessable).
    public_id = models.UUIDField(default=uuid.uuid4, unique=True, editable=False)

    @property
    def is_staff_member(self) -> bool:
        """Therapists and clinic admins work for the clinic; patients do not."""
        return self.role in (Role.THERAPIST, Role.CLINIC_ADMIN)

    @property
    def is_patient(self) -> bool:
        return self.role == Role.PATIENT


class ApiToken(models.Model):
    """A key another system sends as `Authorization: Token <key>`.

    Only the SHA-256 of the key is stored (the key is shown once, when issued), so a copy of the
    database does not hand out working keys. Keys are 256 random bits: a plain hash suffices, no
    slow password hash is needed. A token works only while it is not revoked, not expired, its
    user is active and the user still belongs to the token's clinic.
    """

    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    user = models.ForeignKey(User, on_delete=models.CASCADE, related_name="api_tokens")
    clinic = models.ForeignKey(Clinic, on_delete=models.CASCADE, related_name="api_tokens")
    name = models.CharField(max_length=100)
    prefix = models.CharField(
        max_length=8, help_text="First characters of the key, to tell keys apart."
    )
    key_hash = models.CharField(max_length=64, unique=True)
    created_at = models.DateTimeField(auto_now_add=True)
    created_by = models.ForeignKey(
        User, on_delete=models.SET_NULL, null=True, blank=True, related_name="+"
    )
    expires_at = models.DateTimeField(null=True, blank=True)
    last_used_at = models.DateTimeField(null=True, blank=True)
    revoked_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["-created_at"]

    def __str__(self) -> str:
        return f"{self.name} ({self.prefix}…)"

    @property
    def is_active(self) -> bool:
        from django.utils import timezone

        if self.revoked_at is not None:
            return False
        return self.expires_at is None or self.expires_at > timezone.now()


# The roles' names in the API (the interface contract: "therapist" | "admin" | "patient").
API_ROLES = {"therapist": Role.THERAPIST, "admin": Role.CLINIC_ADMIN, "patient": Role.PATIENT}
ROLE_NAMES = {role: name for name, role in API_ROLES.items()}


class LinkKind(models.TextChoices):
    INVITATION = "invitation", "Invitation"
    PASSWORD = "password", "New password"


class Invitation(models.Model):
    """A one-time link: an invitation to create an account, or a link to set a new password.

    Only the SHA-256 of the link's random key is stored (the link is shown once, to the person
    who made it, and e-mailed when an address is given). A link works once, until `expires_at`.
    An invitation for a patient creates the login of that `patient`; a password link names the
    account (`user`) it is for; an accepted invitation names the account it created.
    """

    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    clinic = models.ForeignKey(Clinic, on_delete=models.CASCADE, related_name="invitations")
    kind = models.CharField(max_length=10, choices=LinkKind.choices, default=LinkKind.INVITATION)
    role = models.CharField(max_length=20, choices=Role.choices)
    patient = models.ForeignKey(
        "patients.Patient", on_delete=models.CASCADE, null=True, blank=True, related_name="+"
    )
    user = models.ForeignKey(
        User, on_delete=models.CASCADE, null=True, blank=True, related_name="account_links"
    )
    email = models.EmailField(blank=True)
    key_hash = models.CharField(max_length=64, unique=True)
    created_by = models.ForeignKey(
        User, on_delete=models.SET_NULL, null=True, blank=True, related_name="+"
    )
    created_at = models.DateTimeField(auto_now_add=True)
    expires_at = models.DateTimeField()
    used_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["-created_at"]

    def __str__(self) -> str:
        return f"{self.get_kind_display()} ({self.get_role_display()})"

    @property
    def is_usable(self) -> bool:
        from django.utils import timezone

        return self.used_at is None and self.expires_at > timezone.now()
