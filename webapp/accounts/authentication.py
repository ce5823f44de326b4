"""DRF authentication by hashed, clinic-scoped, revocable API tokens (`webapp.accounts.tokens`).

Kept apart from the token endpoint: DRF imports this module while it loads its own views.
"""

from __future__ import annotations

import hashlib
from datetime import timedelta
from typing import TYPE_CHECKING

from django.utils import timezone
from rest_framework.authentication import BaseAuthentication, get_authorization_header
from rest_framework.exceptions import AuthenticationFailed

from webapp.accounts.models import ApiToken, User

if TYPE_CHECKING:
    from rest_framework.request import Request

KEYWORD = "Token"
# Writing last_used_at on every call would add a write to every read; a minute is precise enough.
LAST_USED_RESOLUTION = timedelta(minutes=1)


def hash_key(key: str) -> str:
    return hashlib.sha256(key.encode()).hexdigest()


def user_for_key(key: str) -> tuple[User, ApiToken]:
    """The user a key stands for, or AuthenticationFailed (answered as 401)."""
    token = ApiToken.objects.select_related("user").filter(key_hash=hash_key(key)).first()
    if token is None or not token.is_active:
        raise AuthenticationFailed("Invalid, expired or revoked token.")
    user = token.user
    # The scope: a user who left the clinic (or was deactivated) no longer holds its tokens.
    if not user.is_active or user.clinic_id != token.clinic_id:
        raise AuthenticationFailed("Invalid, expired or revoked token.")
    now = timezone.now()
    if token.last_used_at is None or now - token.last_used_at > LAST_USED_RESOLUTION:
        ApiToken.objects.filter(pk=token.pk).update(last_used_at=now)
    return user, token


class ClinicTokenAuthentication(BaseAuthentication):
    """DRF authentication by `Authorization: Token <key>` against hashed `ApiToken` rows."""

    def authenticate(self, request: Request):
        parts = get_authorization_header(request).split()
        if not parts or parts[0].lower() != KEYWORD.lower().encode():
            return None
        if len(parts) != 2:
            raise AuthenticationFailed("Send exactly: Authorization: Token <key>.")
        try:
            key = parts[1].decode()
        except UnicodeError as error:
            raise AuthenticationFailed("The token contains invalid characters.") from error
        user, token = user_for_key(key)
        # The audit log names the token a read came through.
        request._request.api_token = token
        return user, token

    def authenticate_header(self, request: Request) -> str:
        return KEYWORD  # makes unauthenticated calls 401 (with WWW-Authenticate), not 403
