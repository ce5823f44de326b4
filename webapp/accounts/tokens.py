"""Clinic-scoped, revocable API tokens: issuing, checking and the password-for-token endpoint.

`POST /api/v1/auth/token/` (username, password) answers `{"token": "..."}` as the interface
contract says;
each call issues a new token that expires after `settings.API_TOKEN_DAYS`. Staff with two-factor
authentication must also send `otp` (the 6-digit code), so the API is no way around the second
factor. Failed passwords count towards the django-axes lockout exactly like the login page.
"""

from __future__ import annotations

import secrets
from datetime import timedelta

from django.conf import settings
from django.contrib.auth import authenticate
from django.utils import timezone
from django_otp import devices_for_user, user_has_device
from rest_framework import serializers, status
from rest_framework.permissions import AllowAny
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from webapp.accounts.authentication import hash_key
from webapp.accounts.models import ApiToken, User


def issue_token(
    user: User, name: str, created_by: User | None = None, days: int | None = None
) -> tuple[ApiToken, str]:
    """Create a token for `user` in the user's clinic; returns it with the key (shown only now)."""
    if user.clinic_id is None:
        raise ValueError("Only members of a clinic can hold API tokens.")
    key = secrets.token_urlsafe(32)
    expires_at = timezone.now() + timedelta(days=days) if days else None
    token = ApiToken.objects.create(
        user=user,
        clinic_id=user.clinic_id,
        name=name[:100],
        prefix=key[:8],
        key_hash=hash_key(key),
        created_by=created_by,
        expires_at=expires_at,
    )
    return token, key


def revoke_token(token: ApiToken) -> None:
    if token.revoked_at is None:
        token.revoked_at = timezone.now()
        token.save(update_fields=["revoked_at"])


class PasswordForToken(serializers.Serializer):
    username = serializers.CharField()
    password = serializers.CharField(style={"input_type": "password"}, trim_whitespace=False)
    otp = serializers.RegexField(
        r"^\d{6}$", required=False, help_text="Two-factor code, if set up."
    )


class TokenAnswer(serializers.Serializer):
    token = serializers.CharField()
    expires_at = serializers.DateTimeField()


def otp_is_valid(user: User, code: str | None) -> bool:
    if not user_has_device(user):
        return True
    return bool(code) and any(d.verify_token(code) for d in devices_for_user(user))


class ObtainToken(APIView):
    """Exchange a username and password (and two-factor code) for a new API token."""

    authentication_classes: list = []
    permission_classes = [AllowAny]
    serializer_class = PasswordForToken

    def post(self, request: Request) -> Response:
        form = PasswordForToken(data=request.data)
        form.is_valid(raise_exception=True)
        data = form.validated_data
        # The plain HttpRequest: django-axes marks it when the username is locked out.
        http_request = request._request
        user = authenticate(http_request, username=data["username"], password=data["password"])
        if getattr(http_request, "axes_locked_out", False):
            return Response(
                {"detail": "Too many failed logins: this account is locked for a while."},
                status=status.HTTP_429_TOO_MANY_REQUESTS,
            )
        if user is None or user.clinic_id is None:
            return Response(
                {"non_field_errors": ["Unable to log in with the provided credentials."]},
                status=status.HTTP_400_BAD_REQUEST,
            )
        if not otp_is_valid(user, data.get("otp")):
            return Response(
                {"otp": ["This account uses two-factor authentication: send the current code."]},
                status=status.HTTP_400_BAD_REQUEST,
            )
        token, key = issue_token(user, "password login", days=settings.API_TOKEN_DAYS)
        return Response({"token": key, "expires_at": token.expires_at})


obtain_token = ObtainToken.as_view()
