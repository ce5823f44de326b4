"""Optional TOTP two-factor authentication for clinic staff (django-otp).

A staff member who has confirmed an authenticator app must enter a code after the password before
any other page opens; `TwoFactorMiddleware` enforces that for every request.
"""

from __future__ import annotations

import io

import qrcode
import qrcode.image.svg
from django import forms
from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse
from django.shortcuts import redirect, render
from django.urls import reverse
from django_otp import devices_for_user, user_has_device
from django_otp import login as otp_login
from django_otp.plugins.otp_totp.models import TOTPDevice

from webapp.accounts.permissions import require_staff

EXEMPT_PREFIXES = ("/accounts/2fa/verify/", "/accounts/logout/", "/static/", "/healthz")


class CodeForm(forms.Form):
    code = forms.RegexField(
        regex=r"^\d{6}$",
        max_length=6,
        label="6-digit code",
        error_messages={"invalid": "Enter the 6 digits shown in your app."},
    )


def qr_svg(url: str) -> str:
    image = qrcode.make(url, image_factory=qrcode.image.svg.SvgPathImage, box_size=8)
    buffer = io.BytesIO()
    image.save(buffer)
    return buffer.getvalue().decode()


@login_required
@require_staff
def setup(request: HttpRequest) -> HttpResponse:
    device, _ = TOTPDevice.objects.get_or_create(user=request.user, name="default", confirmed=False)
    form = CodeForm(request.POST or None)
    if request.method == "POST" and form.is_valid():
        if device.verify_token(form.cleaned_data["code"]):
            device.confirmed = True
            device.save()
            otp_login(request, device)
            return redirect("dashboard:home")
        form.add_error("code", "That code is not right (or has expired). Try the next one.")
    context = {"form": form, "qr": qr_svg(device.config_url), "secret": device.key}
    return render(request, "registration/2fa_setup.html", context)


@login_required
def verify(request: HttpRequest) -> HttpResponse:
    form = CodeForm(request.POST or None)
    if request.method == "POST" and form.is_valid():
        for device in devices_for_user(request.user):
            if device.verify_token(form.cleaned_data["code"]):
                otp_login(request, device)
                return redirect(request.GET.get("next") or "dashboard:home")
        form.add_error("code", "That code is not right. Try the code shown now.")
    return render(request, "registration/2fa_verify.html", {"form": form})


class TwoFactorMiddleware:
    """Send a staff member with a confirmed device to the code page until they enter a code."""

    def __init__(self, get_response):
        self.get_response = get_response

    def __call__(self, request: HttpRequest) -> HttpResponse:
        user = getattr(request, "user", None)
        if self.must_verify(request, user):
            return redirect(f"{reverse('accounts:2fa-verify')}?next={request.path}")
        return self.get_response(request)

    @staticmethod
    def must_verify(request: HttpRequest, user) -> bool:
        if user is None or not user.is_authenticated or request.path.startswith(EXEMPT_PREFIXES):
            return False
        if request.path.startswith("/api/") and "HTTP_AUTHORIZATION" in request.META:
            return False  # token clients are machines; tokens are scoped and revocable instead
        return not user.is_verified() and user_has_device(user)
