"""django-axes as the first authentication backend, tolerant of calls without a request.

Both ways in from the network pass the request (Django's login view and the token endpoint,
`webapp.accounts.tokens.ObtainToken`), so both count failures and honour lockouts. Only code
calls `authenticate()` without a request (management commands, the test client's `login()`);
there is no one to rate-limit there, and django-axes would otherwise raise.
"""

from __future__ import annotations

from axes.backends import AxesStandaloneBackend
from django.conf import settings
from django.http import HttpResponse, JsonResponse
from django.shortcuts import render


class ClinicAxesBackend(AxesStandaloneBackend):
    def authenticate(self, request, username=None, password=None, **kwargs):
        if request is None:
            return None
        return super().authenticate(request, username=username, password=password, **kwargs)


def lockout_response(request, original_response, credentials) -> HttpResponse:
    """429 for a locked-out username: JSON on the API, the explanatory page elsewhere."""
    limit = settings.AXES_FAILURE_LIMIT
    minutes = round(float(settings.AXES_COOLOFF_TIME) * 60)
    message = (
        f"Too many failed logins ({limit}): this account is locked for {minutes} minutes. "
        "A clinic admin can unlock it sooner."
    )
    if request.path.startswith("/api/"):
        return JsonResponse({"detail": message}, status=429)
    return render(request, "accounts/locked_out.html", {"message": message}, status=429)
