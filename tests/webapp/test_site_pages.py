"""The account menu on every page, error pages, favicon, Help page and the demo clinic admin."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from django.conf import settings
from django.core.management import call_command
from django.test import Client
from django.urls import reverse

from webapp.accounts.models import Clinic, Role, User
from webapp.help import views as help_views

MIGRATIONS = sorted(Path(settings.BASE_DIR, "webapp").glob("*/migrations/*.py"))


def menu_links(html: str) -> set[str]:
    menu = re.search(r'<details class="usermenu">(.*?)</details>', html, re.S)
    assert menu, "no user menu on the page"
    return set(re.findall(r'href="([^"]+)"', menu.group(1)))


@pytest.mark.parametrize(
    ("persona", "expected", "absent"),
    [
        (
            "therapist",
            {"accounts:password-change", "accounts:2fa-setup", "accounts:tokens", "api-docs"},
            {"audit:events"},
        ),
        (
            "clinic_admin",
            {"accounts:password-change", "accounts:tokens", "api-docs", "audit:events"},
            set(),
        ),
        (
            "patient_user",
            {"accounts:password-change"},
            {"accounts:tokens", "accounts:2fa-setup", "audit:events", "api-docs"},
        ),
    ],
)
def test_menu_offers_each_role_its_account_pages(world, client, persona, expected, absent):
    client.force_login(getattr(world, persona))
    home = client.get(reverse("dashboard:home"))
    links = menu_links(home.content.decode())
    assert {reverse(name) for name in expected} <= links
    assert not {reverse(name) for name in absent} & links
    for url in links - {reverse("help:guide")}:
        assert client.get(url).status_code == 200, url


def test_every_linked_account_page_opens_for_staff(world, client):
    client.force_login(world.therapist)
    docs = client.get(reverse("api-docs"))
    assert docs.status_code == 200 and b"swagger" in docs.content.lower()
    assert b"Change password" in client.get(reverse("accounts:password-change")).content
    assert b"<svg" in client.get(reverse("accounts:2fa-setup")).content


def test_patient_gets_the_friendly_403_in_the_layout(world, client):
    client.force_login(world.patient_user)
    response = client.get(reverse("audit:events"))
    assert response.status_code == 403
    html = response.content.decode()
    assert "This page is not available to you" in html
    assert 'class="topbar"' in html and 'class="usermenu"' in html
    assert f'href="{reverse("dashboard:home")}"' in html


def test_404_has_the_layout_and_a_way_home(world, client, settings):
    settings.DEBUG = False
    client.force_login(world.therapist)
    response = client.get("/no/such/page/")
    assert response.status_code == 404
    html = response.content.decode()
    assert "We could not find this page" in html and 'class="topbar"' in html
    assert "Back to the home page" in html


def test_500_page_renders_without_a_request_context(settings):
    settings.DEBUG = False
    settings.ROOT_URLCONF = "tests.webapp.boom_urls"
    response = Client(raise_request_exception=False).get("/boom/")
    assert response.status_code == 500
    html = response.content.decode()
    assert "Something went wrong on our side" in html and 'class="topbar"' in html
    assert "a failure the visitor must not see" not in html


def test_500_falls_back_to_plain_html_when_the_layout_fails(rf, monkeypatch):
    def broken(name):
        raise RuntimeError("template engine down")

    monkeypatch.setattr(help_views.loader, "get_template", broken)
    response = help_views.server_error(rf.get("/"))
    assert response.status_code == 500 and b"Back to the home page" in response.content


def test_favicon_is_linked_and_served(client, db):
    login = client.get(reverse("accounts:login")).content.decode()
    assert re.search(r'<link rel="icon" href="[^"]*favicon\.svg"', login)
    redirect = client.get("/favicon.ico")
    assert redirect.status_code == 302 and redirect["Location"].endswith("favicon.svg")
    icon = client.get(redirect["Location"])
    assert icon.status_code == 200
    assert b"<svg" in b"".join(icon.streaming_content if icon.streaming else [icon.content])


def test_help_page_renders_the_guide_with_its_pictures(client, db):
    page = client.get(reverse("help:guide"))
    assert page.status_code == 200
    html = page.content.decode()
    assert "<h1" in html and "Guide for clinics" in html
    pictures = re.findall(r'<img alt="[^"]+" src="(img/guide-[a-z0-9-]+\.png)"', html)
    assert len(pictures) >= 5
    for picture in pictures:
        image = client.get(reverse("help:guide") + picture)
        assert image.status_code == 200 and image["Content-Type"] == "image/png", picture
        assert b"".join(image.streaming_content).startswith(b"\x89PNG")
    assert client.get(reverse("help:guide") + "img/guide-none.png").status_code == 404
    assert client.get(reverse("help:guide") + "img/..%2FGUIDE.md").status_code == 404


def test_help_link_on_pages_for_visitors_and_users(world, client):
    assert f'href="{reverse("help:guide")}"' in client.get(reverse("accounts:login")).text
    client.force_login(world.therapist)  # the guide is the clinics': patients are not sent there
    assert f'href="{reverse("help:guide")}"' in client.get(reverse("dashboard:home")).text


@pytest.mark.django_db
def test_migrations_alone_create_no_demo_admin():
    # The test database was built by running every migration.
    assert not User.objects.filter(username__startswith="demo-").exists()
    assert not Clinic.objects.filter(name="Demo clinic").exists()
    assert MIGRATIONS and not [m for m in MIGRATIONS if "demo-admin" in m.read_text()]


@pytest.mark.django_db
def test_load_demo_creates_the_clinic_admin_once(client, monkeypatch, settings):
    # Only the accounts are checked here: the recordings' analyses are test_demo.py's (slow) part.
    settings.DEMO_ALLOWED = True
    monkeypatch.setattr("webapp.demo.clinic.load_recordings", lambda *args: None)
    call_command("load_demo")
    call_command("load_demo")
    admin = User.objects.get(username="demo-admin")
    assert admin.role == Role.CLINIC_ADMIN and admin.clinic.name == "Demo clinic"
    therapist = User.objects.get(username="demo-therapist")
    assert admin.clinic_id == therapist.clinic_id
    assert User.objects.filter(role=Role.CLINIC_ADMIN).count() == 1
    assert client.login(username="demo-admin", password="demo-admin-pw")
    assert client.get(reverse("audit:events")).status_code == 200
