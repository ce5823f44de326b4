"""Pages to issue and revoke API tokens.

Staff issue tokens for themselves (e.g. for the practice-management system) and see the key once.
A clinic admin sees and may revoke every token of the clinic; others only their own.
"""

from __future__ import annotations

from django import forms
from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse
from django.shortcuts import get_object_or_404, redirect, render
from django.views.decorators.http import require_POST

from webapp.accounts.models import ApiToken, Role
from webapp.accounts.permissions import require_staff
from webapp.accounts.tokens import issue_token, revoke_token


class NewTokenForm(forms.Form):
    name = forms.CharField(
        max_length=100, help_text="What the token is for, e.g. 'billing system'."
    )
    days = forms.IntegerField(
        min_value=1, max_value=3650, required=False, help_text="Leave empty for no expiry."
    )


def manageable_tokens(user):
    tokens = ApiToken.objects.filter(clinic_id=user.clinic_id).select_related("user")
    if user.role == Role.CLINIC_ADMIN:
        return tokens
    return tokens.filter(user=user)


@login_required
@require_staff
def token_list(request: HttpRequest) -> HttpResponse:
    form = NewTokenForm(request.POST or None)
    new_key = None
    if request.method == "POST" and form.is_valid():
        data = form.cleaned_data
        _, new_key = issue_token(request.user, data["name"], request.user, data["days"])
    context = {"form": form, "tokens": manageable_tokens(request.user), "new_key": new_key}
    return render(request, "accounts/tokens.html", context)


@login_required
@require_staff
@require_POST
def token_revoke(request: HttpRequest, pk) -> HttpResponse:
    token = get_object_or_404(manageable_tokens(request.user), pk=pk)
    revoke_token(token)
    messages.success(request, f"Token {token} revoked: it no longer opens the API.")
    return redirect("accounts:tokens")
