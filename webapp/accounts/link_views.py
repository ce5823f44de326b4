"""The pages a one-time link opens: accept an invitation (choose a username and a password), or
choose a new password. Both log the person in and send them home; a used or expired link
answers 410 with a page that says what to do."""

from __future__ import annotations

from django.contrib import messages
from django.contrib.auth import login
from django.http import Http404, HttpRequest, HttpResponse
from django.shortcuts import redirect, render
from django.views.decorators.cache import never_cache
from django.views.decorators.debug import sensitive_post_parameters

from webapp.accounts import invitations
from webapp.accounts.forms import AcceptInvitationForm, NewPasswordForm
from webapp.accounts.invitations import LinkGoneError
from webapp.accounts.models import Invitation, LinkKind, User
from webapp.audit import log
from webapp.patients.models import Patient

# Sessions made here are checked by this backend on every request: it refuses inactive users.
SESSION_BACKEND = "django.contrib.auth.backends.ModelBackend"


def gone(request: HttpRequest) -> HttpResponse:
    return render(request, "accounts/link_gone.html", status=410)


def open_link(key: str, kind: str) -> Invitation:
    try:
        return invitations.find_link(key, kind)
    except Invitation.DoesNotExist as error:
        raise Http404("No such link.") from error


def log_in(request: HttpRequest, user: User, invitation: Invitation) -> HttpResponse:
    login(request, user, backend=SESSION_BACKEND)
    patient_id = invitation.patient_id
    if patient_id is None:
        patient_id = Patient.objects.filter(user=user).values_list("pk", flat=True).first()
    log.record(
        request, "create" if invitation.kind == LinkKind.INVITATION else "update", user, patient_id
    )
    return redirect("dashboard:home")


@never_cache
@sensitive_post_parameters("password1", "password2")
def accept_invitation(request: HttpRequest, token: str) -> HttpResponse:
    try:
        invitation = open_link(token, LinkKind.INVITATION)
        form = AcceptInvitationForm(request.POST or None)
        if request.method == "POST" and form.is_valid():
            data = form.cleaned_data
            user = invitations.accept_invitation(invitation, data["username"], data["password1"])
            messages.success(request, f"Welcome, {user.username}: your account is ready.")
            return log_in(request, user, invitation)
    except LinkGoneError:
        return gone(request)
    context = {"form": form, "invitation": invitation}
    return render(request, "accounts/invitation_accept.html", context)


class AccountPasswordForm(NewPasswordForm):
    def __init__(self, *args, account: User, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.account = account

    def user_for_checks(self) -> User:
        return self.account


@never_cache
@sensitive_post_parameters("password1", "password2")
def new_password(request: HttpRequest, token: str) -> HttpResponse:
    try:
        invitation = open_link(token, LinkKind.PASSWORD)
        form = AccountPasswordForm(request.POST or None, account=invitation.user)
        if request.method == "POST" and form.is_valid():
            user = invitations.set_new_password(invitation, form.cleaned_data["password1"])
            messages.success(request, "Your new password is set.")
            return log_in(request, user, invitation)
    except LinkGoneError:
        return gone(request)
    return render(request, "accounts/new_password.html", {"form": form, "account": invitation.user})
