"""Login rate limiting (django-axes): the login page and the API token endpoint share one count."""

from __future__ import annotations

import pytest
from django.urls import reverse
from rest_framework.test import APIClient

from tests.personas import PASSWORD
from webapp.accounts.tokens import issue_token

LIMIT = 3


@pytest.fixture(autouse=True)
def _small_limit(settings):
    settings.AXES_FAILURE_LIMIT = LIMIT


def login_page(client, password: str, username: str = "therapist"):
    return client.post(reverse("accounts:login"), {"username": username, "password": password})


def token_endpoint(password: str, username: str = "therapist"):
    return APIClient().post(
        "/api/v1/auth/token/", {"username": username, "password": password}, format="json"
    )


def test_failed_logins_lock_the_account_out(client, world):
    for _ in range(LIMIT - 1):
        assert login_page(client, "wrong").status_code == 200  # the form again, with an error
    assert login_page(client, "wrong").status_code == 429
    # Locked: even the right password is refused, on the page and on the API.
    locked = login_page(client, PASSWORD)
    assert locked.status_code == 429 and "locked" in locked.content.decode()
    assert "_auth_user_id" not in client.session
    assert token_endpoint(PASSWORD).status_code == 429


def test_failures_on_the_token_endpoint_count_too(client, world):
    for _ in range(LIMIT - 1):
        assert token_endpoint("wrong").status_code == 400
    answer = token_endpoint("wrong")
    assert answer.status_code == 429 and "locked" in answer.json()["detail"]
    assert token_endpoint(PASSWORD).status_code == 429
    assert login_page(client, PASSWORD).status_code == 429


def test_a_success_before_the_limit_resets_the_count(client, world):
    for _ in range(LIMIT - 1):
        login_page(client, "wrong")
    assert login_page(client, PASSWORD).status_code == 302
    client.logout()
    for _ in range(LIMIT - 1):
        assert login_page(client, "wrong").status_code == 200
    assert login_page(client, PASSWORD).status_code == 302


def test_guessing_many_usernames_from_one_address_is_locked_too(client, world):
    for name in ("colleague", "patient", "other-patient"):
        login_page(client, "wrong", username=name)
    assert login_page(client, PASSWORD, username="therapist").status_code == 429


def test_existing_tokens_are_not_a_way_to_guess_passwords(world):
    """A token is checked by its hash, never by password: a locked account's tokens keep working
    (revoke them if they leaked) and a wrong token never counts towards or clears a lockout."""
    _, key = issue_token(world.therapist, "billing system")
    for _ in range(LIMIT):
        token_endpoint("wrong")
    client = APIClient()
    client.credentials(HTTP_AUTHORIZATION=f"Token {key}")
    assert client.get("/api/v1/patients/").status_code == 200
    assert token_endpoint(PASSWORD).status_code == 429
