"""Issue 23 in a real browser: the demo clinic's admin invites a therapist and a patient from the
Team page; each opens their link in a browser of their own, chooses a username and a password and
lands on their home page, logged in. The admin then deactivates the new therapist: their API
token answers 401 and their open browser session is logged out on the next page."""

from __future__ import annotations

import pytest

from tests.e2e.conftest import log_in

pytestmark = pytest.mark.e2e

PASSWORD = "a-brand-new-secret-93"


@pytest.fixture
def demo_accounts(transactional_db, monkeypatch, settings):
    """The demo clinic's accounts and patients, without analysing its recordings (slow)."""
    from django.core.management import call_command

    settings.DEMO_ALLOWED = True  # as `make demo` sets it
    monkeypatch.setattr("webapp.demo.clinic.load_recordings", lambda *args: None)
    call_command("load_demo")


def make_link(page, role: str, patient: str | None = None) -> str:
    page.select_option("#id_role", role)
    if patient:
        page.select_option("#id_patient", label=patient)
    with page.expect_navigation():
        page.click("button:has-text('Make the invitation link')")
    return page.locator("#new-link").input_value()


def accept_in_a_fresh_browser(browser, link: str, username: str):
    """A new browser context (no cookies) opens the link and creates the account."""
    context = browser.new_context(viewport={"width": 1280, "height": 900})
    page = context.new_page()
    page.set_default_timeout(30_000)
    page.goto(link)
    assert page.locator("h1").inner_text() == "Create your account"
    page.fill("#id_username", username)
    page.fill("#id_password1", PASSWORD)
    page.fill("#id_password2", PASSWORD)
    page.click("button:has-text('Create my account')")
    page.wait_for_url(lambda url: "/accounts/invitation/" not in url)
    return context, page


def test_admin_invites_then_deactivates(browser, page, live_server, demo_accounts):
    base = live_server.url
    log_in(page, base, "demo-admin")
    page.get_by_role("link", name="Team", exact=True).click()
    page.wait_for_url(f"{base}/accounts/team/")
    therapist_link = make_link(page, "therapist")
    patient_link = make_link(page, "patient", patient="Robin Second")
    for link in (therapist_link, patient_link):
        assert link.startswith(f"{base}/accounts/invitation/")
    assert patient_link != therapist_link

    therapist, therapist_page = accept_in_a_fresh_browser(browser, therapist_link, "sam-therapist")
    assert therapist_page.url == f"{base}/"
    assert therapist_page.locator("h1").inner_text() == "Welcome, sam-therapist"
    assert therapist_page.locator(".mainnav a", has_text="Patients").is_visible()
    patient, patient_page = accept_in_a_fresh_browser(browser, patient_link, "robin")
    assert patient_page.locator("h1").inner_text() == "Welcome, Robin Second"
    assert patient_page.locator(".mainnav a", has_text="Patients").count() == 0
    patient.close()
    assert therapist_page.goto(therapist_link).status == 410  # the link worked once

    login = page.request.post(
        f"{base}/api/v1/auth/token/", form={"username": "sam-therapist", "password": PASSWORD}
    )
    token = {"Authorization": f"Token {login.json()['token']}"}
    assert page.request.get(f"{base}/api/v1/patients/", headers=token).status == 200

    page.goto(f"{base}/accounts/team/")
    row = page.locator("tr[data-username='sam-therapist']")
    page.once("dialog", lambda dialog: dialog.accept())
    row.get_by_role("button", name="Deactivate").click()
    page.wait_for_load_state()
    assert row.locator(".state").inner_text() == "deactivated"

    assert page.request.get(f"{base}/api/v1/patients/", headers=token).status == 401
    therapist_page.goto(f"{base}/patients/")
    assert "/accounts/login/" in therapist_page.url  # logged out on the next page
    therapist.close()
