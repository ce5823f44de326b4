import subprocess
import sys

import pytest
from django.urls import reverse

from tests.personas import PASSWORD


def test_login_page_renders(client):
    response = client.get(reverse("accounts:login"))
    assert response.status_code == 200
    assert b"Log in" in response.content


def test_home_requires_login(client, db):
    response = client.get(reverse("dashboard:home"))
    assert response.status_code == 302
    assert reverse("accounts:login") in response["Location"]


def test_therapist_logs_in_and_sees_dashboard(client, world):
    response = client.post(
        reverse("accounts:login"), {"username": "therapist", "password": PASSWORD}, follow=True
    )
    assert response.status_code == 200
    assert b"Welcome" in response.content
    assert b"Ann Example" in response.content
    assert b"Cy Elsewhere" not in response.content


def test_wrong_password_is_refused(client, world):
    response = client.post(reverse("accounts:login"), {"username": "therapist", "password": "nope"})
    assert response.status_code == 200
    assert b"didn't match" in response.content


def test_patient_sees_only_themselves(client, world):
    client.force_login(world.patient_user)
    response = client.get(reverse("dashboard:home"))
    assert b"Ann Example" in response.content
    assert b"Bob Example" not in response.content


def test_healthz_reports_database(client, db):
    response = client.get("/healthz")
    assert response.status_code == 200
    assert response.json()["database"] is True


def test_healthz_fails_when_broker_is_unreachable(client, db, settings):
    settings.REDIS_URL = "redis://127.0.0.1:1/0"
    response = client.get("/healthz")
    assert response.status_code == 503
    assert response.json()["broker"] is False


@pytest.mark.parametrize(
    ("env", "refused"),
    [
        ({"DEBUG": "0"}, True),
        ({"DEBUG": "0", "SECRET_KEY": "x" * 50}, False),
        ({"DEBUG": "1"}, False),
    ],
)
def test_settings_refuse_production_with_dev_key(env, refused):
    code = (
        "import django, os; os.environ['DJANGO_SETTINGS_MODULE']='webapp.settings'; django.setup()"
    )
    clean_env = {"PATH": "/usr/bin:/bin", **env}
    result = subprocess.run(
        [sys.executable, "-c", code], env=clean_env, capture_output=True, text=True, check=False
    )
    assert (result.returncode != 0) == refused, result.stderr
    if refused:
        assert "SECRET_KEY" in result.stderr


def test_migrations_are_up_to_date():
    result = subprocess.run(
        [sys.executable, "manage.py", "makemigrations", "--check", "--dry-run"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
