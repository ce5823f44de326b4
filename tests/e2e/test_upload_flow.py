"""Uploads as a user makes them, against the site started the way `make run` starts it (server and
a real Celery worker on the filesystem broker, `tests/local_server.py`), never eager tasks:

- the upload page answers at once; the recording page then shows the analysis queued or running,
  its progress moving, and done; the home page lists it under "Analyses under way" meanwhile;
- leaving the exercise blank stores the file and the worker suggests the exercise on the
  recording's page; confirming the suggestion starts the analysis, which finishes; uploading
  the same file again while the first upload still waits for its exercise reuses that upload
  instead of refusing it as a duplicate;
- a bad answer on the form keeps what was typed;
- a worker killed in the middle of an analysis is started again, and the analysis it cut short
  is queued again and finishes.
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest
from playwright.sync_api import Error as PlaywrightError

from tests.e2e.conftest import signed_in_page
from tests.local_server import LocalServer
from tests.personas import PASSWORD

pytestmark = pytest.mark.e2e
DATA = Path(__file__).resolve().parents[2] / "data/ui-prmd"
SQUAT = DATA / "sessions/m01_s02_correct.bvh.gz"
SQUAT_AGAIN = DATA / "sessions/m01_s03_correct.bvh.gz"
ABDUCTION = DATA / "reps/m07_s01_e02.bvh.gz"
SETUP = """
from tests.personas import make_exercise, make_user
from webapp.accounts.models import Clinic, Role
from webapp.patients.models import Patient
clinic = Clinic.objects.create(name="Upload clinic")
therapist = make_user("uploader", clinic, Role.THERAPIST)
patient = Patient.objects.create(clinic=clinic, display_name="Ann Example")
patient.therapists.add(therapist)
make_exercise(clinic, source="reps/m01_s01_e01.bvh.gz")
make_exercise(clinic, name="Shoulder abduction", source="reps/m07_s01_e01.bvh.gz")
"""


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    server = LocalServer(tmp_path_factory.mktemp("make-run"), demo=False, setup=SETUP)
    server.extra_env = {"ANALYSIS_STAGE_DELAY_SECONDS": "0.5"}  # progress long enough to watch
    with server:
        yield server


@pytest.fixture
def user_page(browser, site):
    with signed_in_page(browser, site.url, "uploader", PASSWORD) as page:
        yield page


def submit_upload(page, url: str, path: Path, exercise: str = "", **fields: str) -> float:
    page.goto(f"{url}/recordings/upload/")
    page.select_option("#id_patient", label="Ann Example")
    if exercise:
        page.select_option("#id_exercise", label=exercise)
    for name, value in fields.items():
        page.fill(f"#id_{name}", value)
    page.set_input_files("#id_file", str(path))
    start = time.perf_counter()
    page.click("button[type=submit]")
    page.wait_for_load_state("domcontentloaded")
    return time.perf_counter() - start


READ_STATUS = """() => {
  const box = document.getElementById("run-status");
  if (!box) return [null, null];
  const bar = box.querySelector(".progress");
  return [box.dataset.status, bar ? bar.getAttribute("aria-valuenow") : null];
}"""


def read_status(page) -> tuple[str | None, str | None]:
    """The status box's state; the page reloads itself when the run ends, and a read that meets
    the reload is made again on the new page."""
    for _ in range(5):
        try:
            page.wait_for_load_state("load")
            return tuple(page.evaluate(READ_STATUS))
        except PlaywrightError as error:
            if "context was destroyed" not in str(error) and "navigat" not in str(error):
                raise
            page.wait_for_timeout(200)
    raise AssertionError("the recording page kept navigating")


def watch_until_succeeded(page, site: LocalServer, seconds: float = 360) -> set[int]:
    """Poll the recording page's status (it updates itself) until the analysis succeeds; returns
    the progress values seen. A failed run, a stopped server or the time running out fails the
    test with the end of the server's and worker's log, so a CI failure says what happened."""
    seen: set[int] = set()
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        assert site.running(), "the server stopped:\n" + site.log_tail()
        status, progress = read_status(page)
        if status == "succeeded":
            return seen
        assert status != "failed", "the analysis failed:\n" + site.log_tail()
        seen.add(int(progress or 0))
        page.wait_for_timeout(400)
    raise AssertionError(f"not done after {seconds:.0f} s (status {status}):\n" + site.log_tail())


def test_upload_answers_at_once_and_progress_moves_to_done(user_page, site):
    page = user_page
    seconds = submit_upload(page, site.url, SQUAT, exercise="Deep squat", pain_score="2")
    page.wait_for_url("**/recordings/*/")
    recording_url = page.url
    # The answer came before the analysis ended: the page shows it still under way.
    assert page.get_attribute("#run-status", "data-status") in ("queued", "running")
    assert seconds < 10, f"the upload took {seconds:.1f} s"

    page.goto(f"{site.url}/")
    page.wait_for_selector("#active-list li.run", timeout=30_000)
    assert "Deep squat" in page.inner_text("#active-list")

    page.goto(recording_url)
    seen = watch_until_succeeded(page, site)
    assert len(seen) >= 2, f"progress never moved: {sorted(seen)}"


def test_blank_exercise_is_suggested_confirmed_and_uploading_again_reuses_it(user_page, site):
    page = user_page
    # Bad input first: a pain score out of range. What was typed is kept.
    submit_upload(page, site.url, ABDUCTION, pain_score="11", note="felt fine")
    assert page.input_value("#id_note") == "felt fine"
    assert page.is_visible("#choose-again")

    submit_upload(page, site.url, ABDUCTION, pain_score="1")
    page.wait_for_url("**/recordings/*/")
    first_upload = page.url
    page.wait_for_selector("#suggestion", timeout=60_000)  # the worker recognised it
    assert "Shoulder abduction" in page.inner_text("#suggestion")

    # The uploader leaves without confirming and uploads the same file again: not a duplicate.
    submit_upload(page, site.url, ABDUCTION)
    page.wait_for_url("**/recordings/*/")
    assert page.url == first_upload, "the waiting upload is reused, not stored twice"

    page.wait_for_selector("#confirm-suggestion", timeout=60_000)
    page.click("#confirm-suggestion")
    page.wait_for_selector("#run-status .progress")
    watch_until_succeeded(page, site)

    # Once analysed, the same file again is a duplicate, said in plain words.
    submit_upload(page, site.url, ABDUCTION)
    errors = " ".join(page.locator("p.error").all_inner_texts())
    assert "already uploaded" in errors


def test_an_analysis_cut_short_by_a_killed_worker_is_finished(user_page, site):
    page = user_page
    submit_upload(page, site.url, SQUAT_AGAIN, exercise="Deep squat")
    page.wait_for_url("**/recordings/*/")
    status_url = site.url + page.get_attribute("#run-status", "data-status-url")
    deadline = time.monotonic() + 120
    while True:  # until the worker is in the middle of it
        run = page.request.get(status_url).json()
        if run["status"] == "running" and run["progress"] > 0:
            break
        assert run["status"] in ("queued", "running") and time.monotonic() < deadline, run
        page.wait_for_timeout(50)

    worker = site.worker_pid()
    os.killpg(worker, signal.SIGKILL)  # the worker and its pool, as the out-of-memory killer might
    watch_until_succeeded(page, site)
    assert site.worker_pid() != worker
    assert "starting it again" in site.log_tail(400)
    assert "interrupted analyses: 1 queued again" in site.log_tail(400)
