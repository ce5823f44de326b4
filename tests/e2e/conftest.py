"""A real headless Chromium (Debian's package, never a Playwright download) against live_server.

Chromium missing is an error, not a skip: run tests/e2e/ensure_programs.sh (CI does).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from tests.local_server import LocalServer, made_once, prepared_folder

CHROMIUM = Path(os.environ.get("CHROMIUM", "/usr/bin/chromium"))
# Playwright's sync API keeps an event loop in this thread; the Django ORM calls made by the test
# itself (fixtures) are still synchronous and safe.
os.environ.setdefault("DJANGO_ALLOW_ASYNC_UNSAFE", "true")
os.environ.setdefault("PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD", "1")


@pytest.fixture(scope="module")  # closes its event loop before non-browser tests run
def browser():
    from playwright.sync_api import sync_playwright

    if not CHROMIUM.exists():
        pytest.fail(f"{CHROMIUM} is missing: run tests/e2e/ensure_programs.sh", pytrace=False)
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(
            executable_path=str(CHROMIUM),
            headless=True,
            args=["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
        )
        yield browser
        browser.close()


@pytest.fixture(autouse=True)
def fast_password_hashing(settings):
    """The demo users are created and signed in once per test: the production hasher's
    deliberate slowness would cost seconds each time and is not what these tests look at."""
    settings.PASSWORD_HASHERS = ["django.contrib.auth.hashers.MD5PasswordHasher"]


@pytest.fixture
def page(browser, live_server):
    context = browser.new_context(viewport={"width": 1280, "height": 1000}, accept_downloads=True)
    page = context.new_page()
    page.set_default_timeout(30_000)
    yield page
    context.close()


@pytest.fixture
def eager_celery(settings, tmp_path):
    from workers import app

    settings.MEDIA_ROOT = tmp_path / "media"
    previous = app.conf.task_always_eager
    app.conf.task_always_eager = True
    yield
    app.conf.task_always_eager = previous


def demo_data() -> tuple[Path, Path]:
    """What `load_demo` makes, made once per test run (tests/local_server.py): its rows as a
    fixture file for `loaddata`, and its stored files."""
    root = LocalServer.prepared_root
    assert root is not None, "tests/conftest.py shares the prepared folders"
    folder = prepared_folder(root, demo=True)
    rows = made_once(
        root / "demo.json",
        lambda target: LocalServer(folder).manage(
            "dumpdata", "--natural-foreign", "--exclude=contenttypes", "--exclude=auth.permission",
            "--exclude=sessions", f"--output={target}",
        ),
    )  # fmt: skip
    return rows, folder / "media"


@pytest.fixture
def demo(transactional_db, eager_celery, settings):
    """The demo clinic, as `load_demo` leaves it, in this test's database and media folder.

    `load_demo` analyses its recordings (tens of seconds); its result is loaded instead, the
    same rows and files each time. Only the password hashes are made again, with this test's
    fast hasher (the loader made them with the production one)."""
    from django.contrib.contenttypes.models import ContentType
    from django.core.management import call_command

    from webapp.accounts.models import User
    from webapp.demo.clinic import DEMO_ACCOUNTS

    settings.DEMO_ALLOWED = True
    rows, media = demo_data()
    ContentType.objects.clear_cache()  # the rows name content types by their natural keys
    call_command("loaddata", str(rows), verbosity=0)
    shutil.copytree(media, settings.MEDIA_ROOT, dirs_exist_ok=True)
    for username, password in DEMO_ACCOUNTS:
        user = User.objects.get(username=username)
        user.set_password(password)
        user.save(update_fields=["password"])


@pytest.fixture(scope="session")
def demo_site(tmp_path_factory) -> Iterator[LocalServer]:
    """One site with the demo clinic, started as `make run` starts it, for the whole run of an
    xdist worker. For tests that only read its pages: a test that changes data uses `demo`
    (live_server) or a LocalServer of its own."""
    with LocalServer(tmp_path_factory.mktemp("demo-site"), demo=True) as server:
        yield server


def log_in(
    page, base_url: str, username: str = "demo-therapist", password: str | None = None
) -> None:
    """Sign in through the login form (the demo accounts' password by default)."""
    page.goto(f"{base_url}/accounts/login/")
    page.fill("#id_username", username)
    page.fill("#id_password", password or f"{username}-pw")
    page.click("button[type=submit]")
    page.wait_for_url(lambda url: "/accounts/login" not in url)


@contextmanager
def signed_in_page(browser, base_url: str, username: str, password: str) -> Iterator:
    """A page of its own browser context (1280 × 1000, 60 s timeouts) signed in as ``username``;
    the context is closed afterwards."""
    context = browser.new_context(viewport={"width": 1280, "height": 1000})
    page = context.new_page()
    page.set_default_timeout(60_000)
    try:
        log_in(page, base_url, username, password)
        yield page
    finally:
        context.close()
