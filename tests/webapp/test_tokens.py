"""API tokens: hashed at rest, scoped to one clinic, revocable, expiring; issued three ways."""

from __future__ import annotations

import hashlib
from datetime import timedelta
from io import StringIO

import pytest
from django.core.management import call_command
from django.urls import reverse
from django.utils import timezone
from django_otp.oath import totp
from django_otp.plugins.otp_totp.models import TOTPDevice
from rest_framework.test import APIClient

from tests.personas import PASSWORD
from webapp.accounts.models import ApiToken
from webapp.accounts.tokens import issue_token, revoke_token


def api_with(key: str) -> APIClient:
    client = APIClient()
    client.credentials(HTTP_AUTHORIZATION=f"Token {key}")
    return client


def patients_url(patient=None) -> str:
    return f"/api/v1/patients/{patient.pk}/" if patient else "/api/v1/patients/"


def test_only_the_hash_of_a_key_is_stored(world):
    token, key = issue_token(world.therapist, "billing system")
    row = ApiToken.objects.get(pk=token.pk)
    assert row.key_hash == hashlib.sha256(key.encode()).hexdigest()
    assert key not in {row.key_hash, row.prefix, row.name} and row.prefix == key[:8]
    assert len(key) >= 40 and row.clinic_id == world.clinic.pk


def test_token_of_clinic_a_cannot_read_clinic_b(world):
    _, key = issue_token(world.therapist, "billing system")
    client = api_with(key)
    listed = {p["display_name"] for p in client.get(patients_url()).json()["results"]}
    assert listed == {"Ann Example", "Bob Example"}
    assert client.get(patients_url(world.patient)).status_code == 200
    assert client.get(patients_url(world.outsider_patient)).status_code == 404
    _, outsider_key = issue_token(world.outsider, "their system")
    assert api_with(outsider_key).get(patients_url(world.patient)).status_code == 404


def test_revoked_token_is_401(world):
    token, key = issue_token(world.therapist, "billing system")
    assert api_with(key).get(patients_url()).status_code == 200
    revoke_token(token)
    response = api_with(key).get(patients_url())
    assert response.status_code == 401
    assert response["WWW-Authenticate"] == "Token"


@pytest.mark.parametrize("key", ["not-a-real-key", "a b", ""])
def test_unknown_or_malformed_token_is_401(world, key):
    client = APIClient()
    client.credentials(HTTP_AUTHORIZATION=f"Token {key}".strip())
    assert client.get(patients_url()).status_code == 401


def test_expired_token_is_401(world):
    token, key = issue_token(world.therapist, "short-lived", days=1)
    ApiToken.objects.filter(pk=token.pk).update(expires_at=timezone.now() - timedelta(seconds=1))
    assert api_with(key).get(patients_url()).status_code == 401


def test_token_dies_when_its_user_leaves_the_clinic_or_is_deactivated(world):
    _, key = issue_token(world.therapist, "billing system")
    world.therapist.clinic = world.other_clinic
    world.therapist.save()
    assert api_with(key).get(patients_url()).status_code == 401
    _, colleague_key = issue_token(world.colleague, "billing system")
    world.colleague.is_active = False
    world.colleague.save()
    assert api_with(colleague_key).get(patients_url()).status_code == 401


def test_use_is_recorded(world):
    token, key = issue_token(world.therapist, "billing system")
    assert token.last_used_at is None
    api_with(key).get(patients_url())
    token.refresh_from_db()
    assert token.last_used_at is not None


def test_password_endpoint_issues_an_expiring_token(world, settings):
    settings.API_TOKEN_DAYS = 7
    response = APIClient().post(
        "/api/v1/auth/token/", {"username": "patient", "password": PASSWORD}, format="json"
    )
    assert response.status_code == 200
    key = response.json()["token"]
    token = ApiToken.objects.get(key_hash=hashlib.sha256(key.encode()).hexdigest())
    assert token.user == world.patient_user
    assert timedelta(days=6) < token.expires_at - timezone.now() <= timedelta(days=7)
    # The patient's token reads only their own record.
    assert api_with(key).get(patients_url(world.patient)).status_code == 200
    assert api_with(key).get(patients_url(world.other_patient)).status_code == 404


def test_password_endpoint_asks_staff_with_two_factor_for_the_code(world):
    device = TOTPDevice.objects.create(user=world.therapist, name="phone", confirmed=True)
    form = {"username": "therapist", "password": PASSWORD}
    without = APIClient().post("/api/v1/auth/token/", form, format="json")
    assert without.status_code == 400 and "otp" in without.json()
    code = f"{totp(device.bin_key, step=device.step, digits=device.digits):06d}"
    right = APIClient().post("/api/v1/auth/token/", {**form, "otp": code}, format="json")
    assert right.status_code == 200 and right.json()["token"]
    # A code is good once; after that (or any wrong code) the answer is 400 again.
    replay = APIClient().post("/api/v1/auth/token/", {**form, "otp": code}, format="json")
    assert replay.status_code == 400


def test_management_command_issues_lists_and_revokes(world):
    out = StringIO()
    call_command(
        "api_tokens", "issue", "therapist", "--name", "billing", "--days", "30", stdout=out
    )
    token_id, key = out.getvalue().split()
    assert api_with(key).get(patients_url()).status_code == 200
    listing = StringIO()
    call_command("api_tokens", "list", "--clinic", "North clinic", stdout=listing)
    assert token_id in listing.getvalue() and key not in listing.getvalue()
    call_command("api_tokens", "revoke", token_id, stdout=StringIO())
    assert api_with(key).get(patients_url()).status_code == 401


def test_tokens_page_shows_the_key_once_and_revokes(client, world):
    client.force_login(world.therapist)
    page = client.post(reverse("accounts:tokens"), {"name": "billing system"})
    assert page.status_code == 200
    key = page.context["new_key"]
    assert key and key in page.content.decode()
    again = client.get(reverse("accounts:tokens")).content.decode()
    assert key not in again and key[:8] in again
    token = ApiToken.objects.get(user=world.therapist)
    # A colleague cannot see (so cannot revoke) it; the clinic admin can.
    client.force_login(world.colleague)
    assert client.post(reverse("accounts:token-revoke", kwargs={"pk": token.pk})).status_code == 404
    client.force_login(world.clinic_admin)
    assert client.post(reverse("accounts:token-revoke", kwargs={"pk": token.pk})).status_code == 302
    assert api_with(key).get(patients_url()).status_code == 401
