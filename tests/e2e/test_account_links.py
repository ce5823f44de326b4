"""Item 6 of issue 18 in a real browser: the account pages are reached from the menu under the
user's name, the demo clinic's admin opens the audit log, a patient meets a friendly 403 page,
a wrong address a 404 page with a way home, and the favicon is served."""

from __future__ import annotations

import pytest

from tests.e2e.conftest import log_in

pytestmark = pytest.mark.e2e


@pytest.fixture
def demo_accounts(transactional_db, monkeypatch, settings):
    """The demo loader's accounts and exercises, without analysing its recordings (slow, and
    tested in test_demo.py): the admin under test is the one `load_demo` creates."""
    from django.core.management import call_command

    settings.DEMO_ALLOWED = True
    monkeypatch.setattr("webapp.demo.clinic.load_recordings", lambda *args: None)
    call_command("load_demo")


def open_menu_item(page, label: str) -> None:
    page.click("details.usermenu > summary")
    item = page.locator(".usermenu-items").get_by_role("link", name=label, exact=True)
    item.wait_for(state="visible")
    item.click()
    page.wait_for_load_state()


def test_therapist_reaches_every_account_page_from_the_menu(page, live_server, demo_accounts):
    log_in(page, live_server.url, "demo-therapist")
    assert page.locator(".usermenu-items").is_hidden()  # closed until asked for

    open_menu_item(page, "API tokens")
    assert page.url.endswith("/accounts/tokens/")
    page.fill("#id_name", "billing system")
    page.click("button:has-text('Issue token')")
    assert len(page.locator("#new-key").inner_text()) > 20
    assert page.locator("td", has_text="billing system").count() == 1

    open_menu_item(page, "API documentation")
    page.wait_for_selector(".swagger-ui .opblock", timeout=30_000)  # the schema loaded and drew
    assert page.locator(".opblock-summary-path", has_text="/api/v1/patients/").count() >= 1

    open_menu_item(page, "Two-factor sign-in")
    assert page.locator("h1").inner_text() == "Set up two-factor authentication"
    assert page.locator(".qr svg").count() == 1

    open_menu_item(page, "Change password")
    page.fill("#id_old_password", "demo-therapist-pw")
    page.fill("#id_new_password1", "a-new-therapist-secret-77")
    page.fill("#id_new_password2", "a-new-therapist-secret-77")
    page.click("button:has-text('Change password')")
    assert page.locator("h1").inner_text() == "Password changed"
    assert page.locator(".usermenu-items a", has_text="Audit log").count() == 0


def test_admin_opens_the_audit_log_from_the_menu(page, live_server, demo_accounts):
    log_in(page, live_server.url, "demo-admin")
    assert "Demo clinic" in page.locator("details.usermenu > summary").inner_text()
    open_menu_item(page, "Audit log")
    assert page.url.endswith("/audit/")
    assert page.locator("h1").inner_text() == "Audit log"
    assert page.locator("table.audit tbody tr").count() >= 1  # the admin's own login, at least


def test_patient_meets_a_friendly_403_with_a_way_back(page, live_server, demo_accounts):
    log_in(page, live_server.url, "demo-patient")
    menu = page.locator(".usermenu-items a")
    assert "API tokens" not in menu.all_text_contents()
    response = page.goto(f"{live_server.url}/audit/")
    assert response.status == 403
    assert page.locator("h1").inner_text() == "This page is not available to you"
    assert page.locator("header.topbar").is_visible()  # the site's layout, not a bare 403
    page.get_by_role("link", name="Back to the home page").click()
    page.wait_for_url(f"{live_server.url}/")
    assert page.locator("header.topbar .mainnav").is_visible()


def test_404_page_has_the_layout_and_a_way_home(page, live_server, demo_accounts):
    log_in(page, live_server.url, "demo-therapist")
    response = page.goto(f"{live_server.url}/recordings/not-a-recording/")
    assert response.status == 404
    assert page.locator("h1").inner_text() == "We could not find this page"
    assert page.locator("details.usermenu").is_visible()
    page.get_by_role("link", name="Back to the home page").click()
    page.wait_for_url(f"{live_server.url}/")


def test_favicon_and_help_page(page, live_server, demo_accounts):
    icon = page.goto(f"{live_server.url}/favicon.ico")  # follows the redirect to the SVG
    assert icon.status == 200 and "svg" in icon.headers["content-type"]
    page.goto(f"{live_server.url}/accounts/login/")
    linked = page.locator("link[rel=icon]").get_attribute("href")
    assert page.request.get(f"{live_server.url}{linked}").status == 200
    page.get_by_role("link", name="Help").click()
    assert page.locator("h1").first.inner_text() == "Guide for clinics"
