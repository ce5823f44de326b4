"""The clinic admin's "Team" page (accounts, invitations, password links) and a therapist's
invitation of their own patient from the patient page. Every change is audited."""

from __future__ import annotations

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.core.exceptions import PermissionDenied
from django.http import Http404, HttpRequest, HttpResponse
from django.shortcuts import get_object_or_404, redirect, render
from django.utils import timezone
from django.views.decorators.http import require_POST

from webapp.accounts import invitations
from webapp.accounts.forms import InviteForm, PatientInviteForm
from webapp.accounts.models import Invitation, Role, User
from webapp.accounts.permissions import get_patient_for_user, require_clinic_admin, require_staff
from webapp.audit import log
from webapp.patients.models import Patient


def new_link_context(request: HttpRequest, invitation: Invitation, key: str) -> dict:
    """What the page shows once: the whole link, and whether it was e-mailed."""
    url = request.build_absolute_uri(invitations.link_path(invitation, key))
    return {"link": url, "emailed": invitations.send_link(invitation, url), "link_for": invitation}


def team_context(request: HttpRequest, form: InviteForm, new_link: dict | None = None) -> dict:
    clinic_id = request.user.clinic_id
    accounts = User.objects.filter(clinic_id=clinic_id).order_by("role", "username")
    patients = dict(
        Patient.objects.filter(clinic_id=clinic_id, user__isnull=False).values_list(
            "user_id", "display_name"
        )
    )
    rows = [(account, patients.get(account.pk, "")) for account in accounts]
    pending = Invitation.objects.filter(
        clinic_id=clinic_id, used_at__isnull=True, expires_at__gt=timezone.now()
    ).select_related("patient", "user", "created_by")
    return {"form": form, "rows": rows, "pending": pending, **(new_link or {})}


@login_required
@require_clinic_admin
def team(request: HttpRequest) -> HttpResponse:
    form = InviteForm(request.POST or None, clinic_id=request.user.clinic_id)
    new_link = None
    if request.method == "POST" and form.is_valid():
        data = form.cleaned_data
        try:
            invitation, key = invitations.create_invitation(
                request.user, data["role"], data["patient"], data["email"]
            )
        except ValueError as error:
            form.add_error(None, str(error))
        else:
            log.record(request, "create", invitation, patient_id=invitation.patient_id)
            new_link = new_link_context(request, invitation, key)
            form = InviteForm(clinic_id=request.user.clinic_id)
    return render(request, "accounts/team.html", team_context(request, form, new_link))


def clinic_account(request: HttpRequest, pk) -> User:
    try:
        return invitations.account_in_clinic(request.user, pk)
    except User.DoesNotExist as error:
        raise Http404("No such account in this clinic.") from error


def patient_id_of(account: User):
    return Patient.objects.filter(user=account).values_list("pk", flat=True).first()


@login_required
@require_clinic_admin
@require_POST
def set_active(request: HttpRequest, pk, active: bool) -> HttpResponse:
    account = clinic_account(request, pk)
    try:
        invitations.set_active(request.user, account, active)
    except ValueError as error:
        messages.error(request, str(error))
        return redirect("accounts:team")
    log.record(request, "update", account, patient_id=patient_id_of(account))
    if active:
        messages.success(request, f"{account.username} can log in again.")
    else:
        messages.success(
            request,
            f"{account.username} is deactivated: logged out everywhere, API tokens revoked.",
        )
    return redirect("accounts:team")


@login_required
@require_clinic_admin
@require_POST
def password_link(request: HttpRequest, pk) -> HttpResponse:
    account = clinic_account(request, pk)
    invitation, key = invitations.create_password_link(request.user, account)
    log.record(request, "update", account, patient_id=patient_id_of(account))
    form = InviteForm(clinic_id=request.user.clinic_id)
    context = team_context(request, form, new_link_context(request, invitation, key))
    return render(request, "accounts/team.html", context)


@login_required
@require_clinic_admin
@require_POST
def withdraw_link(request: HttpRequest, pk) -> HttpResponse:
    invitation = get_object_or_404(
        Invitation, pk=pk, clinic_id=request.user.clinic_id, used_at__isnull=True
    )
    Invitation.objects.filter(pk=invitation.pk).update(expires_at=timezone.now())
    log.record(request, "delete", invitation, patient_id=invitation.patient_id)
    messages.success(request, "The link is withdrawn: it no longer works.")
    return redirect("accounts:team")


@login_required
@require_staff
def invite_patient(request: HttpRequest, pk) -> HttpResponse:
    """From the patient page: a login for this patient (their therapist or a clinic admin)."""
    patient = get_patient_for_user(request, pk)
    if not invitations.may_invite(request.user, Role.PATIENT, patient):
        raise PermissionDenied(
            "Only the patient's own therapist or a clinic admin can invite them."
        )
    form = PatientInviteForm(request.POST or None)
    context = {"patient": patient, "form": form}
    if request.method == "POST" and form.is_valid():
        try:
            invitation, key = invitations.create_invitation(
                request.user, Role.PATIENT, patient, form.cleaned_data["email"]
            )
        except ValueError as error:
            form.add_error(None, str(error))
        else:
            log.record(request, "create", invitation, patient_id=patient.pk)
            context |= new_link_context(request, invitation, key)
    return render(request, "accounts/invite_patient.html", context)
