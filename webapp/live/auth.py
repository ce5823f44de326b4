"""Who is on the other end of a live-session WebSocket: an API token (capture clients send
``Authorization: Token ...`` or ``?token=...``) or the browser's signed-in session."""

from __future__ import annotations

from typing import Any
from urllib.parse import parse_qs

from channels.db import database_sync_to_async
from channels.security.websocket import AllowedHostsOriginValidator
from rest_framework.exceptions import AuthenticationFailed

from webapp.accounts.authentication import KEYWORD, user_for_key
from webapp.accounts.models import User


def token_from_scope(scope: dict[str, Any]) -> str | None:
    """The token a WebSocket handshake carries (header first, then the query string)."""
    for name, value in scope.get("headers", ()):
        if name.lower() == b"authorization":
            parts = value.decode("latin-1").split()
            if len(parts) == 2 and parts[0].lower() == KEYWORD.lower():
                return parts[1]
            return ""  # a malformed header is refused, never ignored
    query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
    values = query.get("token")
    return values[0] if values else None


@database_sync_to_async
def _token_user(key: str) -> User | None:
    try:
        user, _ = user_for_key(key)
    except AuthenticationFailed:
        return None
    return user


async def scope_user(scope: dict[str, Any]) -> User | None:
    """The authenticated user, or None (a wrong token never falls back to the session)."""
    key = token_from_scope(scope)
    if key is not None:
        return await _token_user(key) if key else None
    user = scope.get("user")
    if user is None or not getattr(user, "is_authenticated", False):
        return None
    return user


class BrowserOriginCheck:
    """Browsers always send ``Origin``: it must be one of ALLOWED_HOSTS (no cross-site use of the
    session cookie). A capture client sends none: its cookies are dropped, so only a token can
    authenticate it."""

    def __init__(self, app: Any) -> None:
        self.app = app
        self.checked = AllowedHostsOriginValidator(app)

    async def __call__(self, scope: dict[str, Any], receive: Any, send: Any) -> Any:
        headers = scope.get("headers", [])
        if scope["type"] == "websocket" and not any(n == b"origin" for n, _ in headers):
            scope = {**scope, "headers": [(n, v) for n, v in headers if n != b"cookie"]}
            return await self.app(scope, receive, send)
        return await self.checked(scope, receive, send)
