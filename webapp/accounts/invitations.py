"""Invitations and password links: one-time links that expire, and switching accounts off and on.

A clinic admin invites therapists, admins and patients and sends any account of the clinic a
link to set a new password; a therapist invites the patients they look after. The random key is
in the link only: the database keeps its SHA-256 (`Invitation.key_hash`), so a copy of the
database opens no account. Using a link marks it used with a conditional UPDATE, so two
submissions of one link cannot both succeed. Every step is audited by the views that call these.
"""

from __future__ import annotations

import secrets
from datetime import timedelta

from django.conf import settings
from django.core.exceptions import PermissionDenied
from django.core.mail import send_mail
from django.db import transaction
from django.urls import reverse
from django.utils import timezone

from webapp.accounts.authentication import hash_key
from webapp.accounts.models import ApiToken, Invitation, LinkKind, Role, User
from webapp.patients.models import Patient

# Days a link stays usable (settings.INVITATION_DAYS overrides).
DEFAULT_DAYS = 7


class LinkGoneError(Exception):
    """The link was used already, has expired, or no longer fits (answered as 410)."""


def link_days() -> int:
    return int(getattr(settings, "INVITATION_DAYS", DEFAULT_DAYS))


def link_path(invitation: Invitation, key: str) -> str:
    name = (
        "accounts:invitation" if invitation.kind == LinkKind.INVITATION else "accounts:new-password"
    )
    return reverse(name, kwargs={"token": key})


def may_invite(user: User, role: str, patient: Patient | None) -> bool:
    """Clinic admins invite anyone to their clinic; therapists only the patients they look after."""
    if user.clinic_id is None or (patient is not None and patient.clinic_id != user.clinic_id):
        return False
    if user.role == Role.CLINIC_ADMIN:
        return True
    if user.role != Role.THERAPIST or role != Role.PATIENT or patient is None:
        return False
    return patient.therapists.filter(pk=user.pk).exists()


def check_invitation(inviter: User, role: str, patient: Patient | None) -> None:
    """ValueError for an invitation that cannot be made, PermissionDenied for one not allowed."""
    if role == Role.PATIENT and patient is None:
        raise ValueError("Choose the patient this login is for.")
    if role != Role.PATIENT and patient is not None:
        raise ValueError("Only a patient's login is linked to a patient.")
    if not may_invite(inviter, role, patient):
        raise PermissionDenied("Only a clinic admin, or the patient's own therapist, can invite.")
    if patient is not None and patient.user_id is not None:
        raise ValueError(f"{patient.display_name} already has a login.")


def new_link(clinic_id: int, created_by: User, **fields) -> tuple[Invitation, str]:
    key = secrets.token_urlsafe(32)
    invitation = Invitation.objects.create(
        clinic_id=clinic_id,
        key_hash=hash_key(key),
        created_by=created_by,
        expires_at=timezone.now() + timedelta(days=link_days()),
        **fields,
    )
    return invitation, key


def create_invitation(
    inviter: User, role: str, patient: Patient | None = None, email: str = ""
) -> tuple[Invitation, str]:
    """A new invitation and its link's key (shown only now); see `check_invitation`."""
    check_invitation(inviter, role, patient)
    return new_link(inviter.clinic_id, inviter, role=role, patient=patient, email=email)


def create_password_link(admin: User, account: User) -> tuple[Invitation, str]:
    """A one-time link for `account` (of the admin's clinic) to choose a new password."""
    if admin.role != Role.CLINIC_ADMIN or account.clinic_id != admin.clinic_id:
        raise PermissionDenied("Only the clinic admin can send a new password link.")
    return new_link(
        admin.clinic_id,
        admin,
        kind=LinkKind.PASSWORD,
        role=account.role,
        user=account,
        email=account.email,
    )


def send_link(invitation: Invitation, url: str) -> bool:
    """E-mail the link (Django's mail settings; the console by default) when there is an address."""
    if not invitation.email:
        return False
    clinic = invitation.clinic.name
    if invitation.kind == LinkKind.INVITATION:
        subject = f"Your invitation to {clinic}'s physio dashboard"
        body = f"{clinic} invites you to the physio dashboard. Choose your username and password:"
    else:
        subject = f"A new password for {clinic}'s physio dashboard"
        body = "Choose a new password for your account on the physio dashboard:"
    days = link_days()
    body += f"\n\n{url}\n\nThe link works once, for {days} days."
    send_mail(subject, body, None, [invitation.email])
    return True


def find_link(key: str, kind: str) -> Invitation:
    """The link of this key: Invitation.DoesNotExist (404); LinkGoneError (410) if spent or late."""
    invitation = Invitation.objects.select_related("clinic", "patient", "user").get(
        key_hash=hash_key(key), kind=kind
    )
    if not invitation.is_usable:
        raise LinkGoneError
    return invitation


def spend(invitation: Invitation) -> None:
    """Mark the link used; LinkGoneError if another request used it first (or it just expired)."""
    now = timezone.now()
    claimed = Invitation.objects.filter(
        pk=invitation.pk, used_at__isnull=True, expires_at__gt=now
    ).update(used_at=now)
    if not claimed:
        raise LinkGoneError
    invitation.used_at = now


@transaction.atomic
def accept_invitation(invitation: Invitation, username: str, password: str) -> User:
    """Create the invited account (its patient linked for a patient's login) and spend the link."""
    spend(invitation)
    user = User(
        username=username,
        email=invitation.email,
        clinic_id=invitation.clinic_id,
        role=invitation.role,
    )
    user.set_password(password)
    user.save()
    if invitation.patient_id is not None:
        linked = Patient.objects.filter(pk=invitation.patient_id, user__isnull=True).update(
            user=user
        )
        if not linked:
            raise LinkGoneError  # the patient was given a login meanwhile (or deleted): undo all
    Invitation.objects.filter(pk=invitation.pk).update(user=user)
    return user


@transaction.atomic
def set_new_password(invitation: Invitation, password: str) -> User:
    spend(invitation)
    user = invitation.user
    if user is None or not user.is_active:
        raise LinkGoneError
    user.set_password(password)
    user.save(update_fields=["password"])
    return user


def account_in_clinic(admin: User, public_id) -> User:
    """A user of the admin's clinic, or User.DoesNotExist (404) for anyone else's."""
    return User.objects.get(public_id=public_id, clinic_id=admin.clinic_id)


def set_active(admin: User, account: User, active: bool) -> None:
    """Switch an account off (its sessions end on their next request, its API tokens are revoked)
    or on again. An admin cannot switch off their own account."""
    if account.pk == admin.pk and not active:
        raise ValueError("You cannot deactivate your own account.")
    with transaction.atomic():
        User.objects.filter(pk=account.pk).update(is_active=active)
        if not active:
            tokens = ApiToken.objects.filter(user=account, revoked_at__isnull=True)
            tokens.update(revoked_at=timezone.now())
    account.is_active = active
