"""A patient uploads without naming the exercise, against the site started the way `make run`
starts it (server and a real Celery worker on the filesystem broker, `tests/local_server.py`):

- the upload form lists only the exercises prescribed to the patient;
- the upload answers at once with the recording's page, which shows the worker recognising the
  exercise and then its suggestion, offering only the prescribed exercises;
- confirming the suggestion starts the analysis, which finishes.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from tests.e2e.conftest import signed_in_page
from tests.e2e.test_upload_flow import watch_until_succeeded
from tests.local_server import LocalServer
from tests.personas import PASSWORD

pytestmark = pytest.mark.e2e
DATA = Path(__file__).resolve().parents[2] / "data/ui-prmd"
ABDUCTION = DATA / "reps/m07_s01_e02.bvh.gz"
SETUP = """
import datetime
from tests.personas import make_exercise, make_user
from webapp.accounts.models import Clinic, Role
from webapp.patients.models import Patient, Prescription
clinic = Clinic.objects.create(name="Recognition clinic")
user = make_user("recogniser", clinic, Role.PATIENT)
patient = Patient.objects.create(clinic=clinic, user=user, display_name="Ann Example")
squat = make_exercise(clinic, source="reps/m01_s01_e01.bvh.gz")
abduction = make_exercise(clinic, name="Shoulder abduction", source="reps/m07_s01_e01.bvh.gz")
make_exercise(clinic, name="Standing lunge", source="reps/m01_s01_e01.bvh.gz")
for exercise in (squat, abduction):
    today = datetime.date.today()
    Prescription.objects.create(patient=patient, exercise=exercise, start_date=today)
"""
PRESCRIBED = ["Deep squat", "Shoulder abduction"]


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    server = LocalServer(tmp_path_factory.mktemp("make-run"), demo=False, setup=SETUP)
    with server:
        yield server


@pytest.fixture
def patient_page(browser, site):
    with signed_in_page(browser, site.url, "recogniser", PASSWORD) as page:
        yield page


def option_texts(page, selector: str) -> list[str]:
    return page.eval_on_selector_all(f"{selector} option", "os => os.map(o => o.text.trim())")


def test_recognised_on_the_recording_page_then_confirmed_and_analysed(patient_page, site):
    page = patient_page
    page.goto(f"{site.url}/recordings/upload/")
    assert [t for t in option_texts(page, "#id_exercise") if t.strip("-")] == PRESCRIBED
    page.set_input_files("#id_file", str(ABDUCTION))
    start = time.perf_counter()
    with page.expect_response(lambda r: r.request.method == "POST") as answer:
        page.click("button[type=submit]")
    seconds = time.perf_counter() - start
    assert answer.value.status == 302 and seconds < 5, f"the upload took {seconds:.1f} s"
    page.wait_for_url("**/recordings/*/")
    # Usually still under way when the page comes: its progress is shown; a fast worker may
    # already be done, and the page shows the suggestion at once.
    page.wait_for_selector("#recognition-waiting, #suggestion")
    if page.is_visible("#recognition-waiting"):
        assert "Finding out which exercise this is" in page.inner_text("#recognition")
        assert page.is_visible("#recognition .progress")

    # The page follows the worker (it reloads itself when the recognition ends).
    page.wait_for_selector("#suggestion", timeout=60_000)
    assert "Shoulder abduction" in page.inner_text("#suggestion")
    assert not page.is_visible("#recognition-waiting")
    assert option_texts(page, "#recognition-exercise") == PRESCRIBED
    assert page.get_attribute("#run-status", "data-status") == ""  # nothing analysed yet

    page.click("#confirm-suggestion")
    page.wait_for_selector("#run-status .progress")
    assert page.get_attribute("#run-status", "data-status") in ("queued", "running", "succeeded")
    watch_until_succeeded(page, site)
    assert "Shoulder abduction" in page.inner_text("h1")
