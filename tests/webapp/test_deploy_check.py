"""`manage.py check --deploy` is clean under production settings (DEBUG off, real secret key)."""

from __future__ import annotations

import os
import secrets
import subprocess
import sys
from pathlib import Path

import pytest
from django.core.checks.security import base as security_checks

ROOT = Path(__file__).resolve().parents[2]
# Settings the production environment must not override for this check to speak for the defaults.
SECURITY_VARIABLES = (
    "DEBUG",
    "SECRET_KEY",
    "ALLOWED_HOSTS",
    "SESSION_COOKIE_SECURE",
    "CSRF_COOKIE_SECURE",
    "SECURE_SSL_REDIRECT",
    "SECURE_HSTS_SECONDS",
    "SECURE_HSTS_INCLUDE_SUBDOMAINS",
    "SECURE_HSTS_PRELOAD",
    "AXES_LOCKOUT_BY",
    # The browser tests set this for their own process (Playwright's event loop); a real
    # deployment never has it, and Django's deploy check rightly refuses it.
    "DJANGO_ALLOW_ASYNC_UNSAFE",
)


def production_env(tmp_path: Path, **overrides: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in SECURITY_VARIABLES}
    env.pop("DJANGO_SETTINGS_MODULE", None)
    env.update(
        DEBUG="0",
        SECRET_KEY=secrets.token_urlsafe(50),
        ALLOWED_HOSTS="clinic.example.org",
        DATA_DIR=str(tmp_path),
        **overrides,
    )
    return env


def manage(env: dict[str, str], *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "manage.py", *args],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


def test_check_deploy_is_clean_in_production(tmp_path):
    result = manage(production_env(tmp_path), "check", "--deploy", "--fail-level", "WARNING")
    assert result.returncode == 0, result.stdout + result.stderr
    assert "System check identified no issues (0 silenced)." in result.stdout


def test_production_refuses_the_development_secret_key(tmp_path):
    env = production_env(tmp_path)
    env.pop("SECRET_KEY")
    result = manage(env, "check")
    assert result.returncode != 0 and "Set SECRET_KEY" in result.stderr


@pytest.mark.parametrize(
    ("setting", "value", "check"),
    [
        ("SECURE_HSTS_SECONDS", 0, security_checks.check_sts),
        ("SECURE_SSL_REDIRECT", False, security_checks.check_ssl_redirect),
        ("DEBUG", True, security_checks.check_debug),
    ],
)
def test_the_deploy_checks_do_see_weakened_settings(settings, setting, value, check):
    """The checks the subprocess runs are not vacuous: each flags its weakened setting."""
    settings.DEBUG = False
    settings.SECURE_HSTS_SECONDS = 31536000
    settings.SECURE_SSL_REDIRECT = True
    assert check(None) == []
    setattr(settings, setting, value)
    assert len(check(None)) == 1
