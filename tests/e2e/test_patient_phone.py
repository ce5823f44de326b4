"""A patient's pages on a 390 × 844 phone, in a real browser (issue 24, items 1 and 5).

A patient signs in, uploads a session of their prescribed exercise (saying how hard it felt), and
its analysis runs (eager tasks). Then every page they can reach from the site's menus, today's
plan, upload, the session's result, progress, the account pages, must:

- fit the phone's width (no horizontal scrolling);
- have no "serious" or "critical" accessibility violation by axe-core (node_modules, injected by
  the test, never served by the site);
- contain none of the therapist's technical words.

And with the keyboard alone, Tab reaches the upload form's fields and the user menu, which opens
with Enter and shows every item inside the screen.
"""

from __future__ import annotations

import datetime
from pathlib import Path

import pytest
from django.urls import reverse

from tests.personas import PASSWORD, make_exercise, make_user

pytestmark = pytest.mark.e2e
ROOT = Path(__file__).resolve().parents[2]
AXE = ROOT / "node_modules" / "axe-core" / "axe.min.js"
SESSION = ROOT / "data/ui-prmd/sessions/m01_s01_correct.bvh.gz"
PHONE = {"width": 390, "height": 844}
THERAPIST_WORDS = (
    "key pose", "level", "% of its range", "refining", "Order check", "normal range", "GBDTW",
    "landmark",
)  # fmt: skip
USERNAME = "phone-patient"


@pytest.fixture
def patient_world(transactional_db, eager_celery):
    from webapp.accounts.models import Clinic, Role
    from webapp.patients.models import Goal, Patient, Prescription

    clinic = Clinic.objects.create(name="Harbour clinic")
    user = make_user(USERNAME, clinic, Role.PATIENT)
    patient = Patient.objects.create(clinic=clinic, user=user, display_name="Ann Example")
    squat = make_exercise(clinic, source="reps/m01_s01_e01.bvh.gz")
    today = datetime.date.today()
    Prescription.objects.create(
        patient=patient, exercise=squat, start_date=today, sets=3, target_repetitions=10,
        hold_seconds=2, notes="Keep your heels on the floor.",
    )  # fmt: skip
    Goal.objects.create(
        patient=patient, exercise=squat, measure="knee_flexion_left", target=100,
        by=today + datetime.timedelta(days=60),
    )  # fmt: skip
    return patient


@pytest.fixture
def phone(browser, live_server, patient_world):
    context = browser.new_context(viewport=PHONE)
    page = context.new_page()
    page.set_default_timeout(60_000)
    page.goto(f"{live_server.url}/accounts/login/")
    page.fill("#id_username", USERNAME)
    page.fill("#id_password", PASSWORD)
    page.click("button[type=submit]")
    page.wait_for_url(lambda url: "/accounts/login" not in url)
    yield page
    context.close()


def serious_violations(page) -> list[str]:
    page.add_script_tag(content=AXE.read_text(encoding="utf-8"))
    found = page.evaluate(
        """async () => (await axe.run(document)).violations
             .filter(v => v.impact === 'serious' || v.impact === 'critical')
             .map(v => `${v.id}: ${v.nodes.map(n => n.target.join(' ')).join(', ')}`)"""
    )
    return list(found)


def check_page(page) -> None:
    """The three promises of every patient page, with the page's address in any failure."""
    where = page.url
    width = page.evaluate("document.documentElement.scrollWidth")
    assert width <= PHONE["width"], f"{where} is {width} px wide"
    assert serious_violations(page) == [], where
    text = page.inner_text("body").lower()
    spoken = [word for word in THERAPIST_WORDS if word.lower() in text]
    assert spoken == [], f"{where} says {spoken}"


def upload_session(page, base_url: str) -> None:
    page.goto(base_url + reverse("recordings:upload"))
    check_page(page)
    page.select_option("#id_exercise", label="Deep squat")
    page.set_input_files("#id_file", str(SESSION))
    page.fill("#id_effort", "5")
    page.click("button[type=submit]")  # the analysis runs within the request (eager tasks)
    page.wait_for_url("**/recordings/*/", timeout=600_000)


def test_every_patient_page_fits_a_phone_is_accessible_and_plain(phone, live_server):
    from webapp.recordings.models import Recording

    base = live_server.url
    check_page(phone)  # today's plan, before any session
    assert "3 sets of 10 repetitions" in phone.inner_text("#prescriptions")
    assert "Keep your heels on the floor." in phone.inner_text("#prescriptions")
    phone.wait_for_selector(".reference-view[data-ready='1']")  # the reference moves in 3D

    upload_session(phone, base)
    recording = Recording.objects.get()
    assert recording.effort == 5
    assert phone.get_attribute("#run-status", "data-status") == "succeeded"
    done = int(phone.inner_text("#reps-done"))
    assert done == recording.runs.first().result.repetition_count > 0
    assert 0 <= int(phone.inner_text("#reps-well")) <= done
    check_page(phone)

    phone.goto(base + reverse("dashboard:home"))
    check_page(phone)
    assert phone.locator("#last-result #reps-done").inner_text() == str(done)
    phone.goto(base + reverse("dashboard:my-progress"))
    check_page(phone)
    assert phone.locator(".exercise-progress").count() == 1  # one chart per exercise
    assert "goal 100° by" in phone.inner_text(".range-chart")
    for name in ("accounts:password-change", "accounts:password-changed"):
        phone.goto(base + reverse(name))
        assert phone.locator("h1").count() == 1, name  # the page itself, not a 404
        check_page(phone)


def tab_until(page, predicate: str, most: int = 40) -> bool:
    """Press Tab until the focused element matches the JavaScript predicate (on `el`)."""
    for _ in range(most):
        page.keyboard.press("Tab")
        if page.evaluate(f"(() => {{ const el = document.activeElement; return {predicate}; }})()"):
            return True
    return False


def test_keyboard_reaches_the_upload_fields_and_the_user_menu(phone, live_server):
    phone.goto(live_server.url + reverse("recordings:upload"))
    phone.keyboard.press("Tab")
    assert phone.evaluate("document.activeElement.className") == "skip-link"
    for field in ("id_exercise", "id_file", "id_pain_score", "id_effort", "id_note"):
        assert tab_until(phone, f"el.id === '{field}'"), field
        label = phone.locator(f"label[for={field}]")
        assert label.count() == 1 and label.inner_text().strip(), field

    phone.goto(live_server.url + reverse("dashboard:home"))
    assert tab_until(phone, "el.matches('details.usermenu > summary')")
    outline = phone.evaluate("getComputedStyle(document.activeElement).outlineStyle")
    assert outline != "none"  # the focus is visible
    phone.keyboard.press("Enter")
    items = phone.locator(".usermenu-items a, .usermenu-items button")
    assert items.count() >= 2
    for i in range(items.count()):
        box = items.nth(i).bounding_box()
        assert box is not None and box["x"] >= 0 and box["x"] + box["width"] <= PHONE["width"]
    assert tab_until(phone, "el.textContent.trim() === 'Change password'", most=3)
    assert phone.evaluate("document.documentElement.scrollWidth") <= PHONE["width"]
