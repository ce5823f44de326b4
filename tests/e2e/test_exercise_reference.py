"""A therapist changes an exercise through its pages: plays the reference on its own, replaces
it with a new recording (an earlier result keeps its score and model version) and adds a feedback
rule by picking, which then appears in the rules' text."""

from __future__ import annotations

import pytest
from django.urls import reverse

from tests.personas import FIXTURES, PASSWORD, make_exercise, make_recording, make_user

pytestmark = pytest.mark.e2e
NEW_REFERENCE = FIXTURES / "reps" / "m01_s01_e03.bvh.gz"


@pytest.fixture
def analysed(transactional_db, eager_celery):
    from webapp.accounts.models import Clinic, Role
    from webapp.patients.models import Patient
    from workers.analysis_task import analyse_run

    clinic = Clinic.objects.create(name="Reference clinic")
    user = make_user("referee", clinic, Role.THERAPIST)
    patient = Patient.objects.create(clinic=clinic, display_name="Ann Example")
    exercise = make_exercise(clinic)
    recording = make_recording(patient, exercise)
    assert analyse_run(str(recording.runs.get().pk)) == "succeeded"
    return user, exercise, recording


def log_in(page, base_url: str, user) -> list[str]:
    """Signs in; the returned list collects the page's JavaScript errors from now on."""
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.goto(f"{base_url}/accounts/login/")
    page.fill("#id_username", user.username)
    page.fill("#id_password", PASSWORD)
    page.click("button[type=submit]")
    page.wait_for_url(lambda url: "/accounts/login" not in url)
    return errors


def result(page, base_url: str, recording) -> dict:
    path = reverse("recordings:result", kwargs={"pk": recording.pk})
    return page.evaluate(f"async () => (await fetch('{base_url}{path}')).json()")


def test_reference_plays_is_replaced_and_a_rule_is_picked(page, live_server, analysed):
    user, exercise, recording = analysed
    errors = log_in(page, live_server.url, user)
    before = result(page, live_server.url, recording)
    assert before["model_version"] == 1 and before["metrics"]["score"] is not None

    # The reference plays on its own on the exercise page.
    page.goto(f"{live_server.url}/exercises/{exercise.pk}/")
    page.wait_for_selector("#reference-player[data-ready='1']", state="attached")
    assert page.locator("#reference-canvas").is_visible()
    page.click("#reference-play")
    page.wait_for_function("window.referencePlayer.frame > 5")
    assert page.inner_text("#reference-play") == "Pause"
    assert page.inner_text("#reference-player [data-clock]").endswith(" s")

    # Replace the reference through the page.
    old_frames = list(exercise.tutor_landmark_frames)
    page.click("a.button:has-text('Replace the reference')")
    page.set_input_files("#id_tutor", str(NEW_REFERENCE))
    page.click("button[type=submit]")
    page.wait_for_url(f"{live_server.url}/exercises/{exercise.pk}/annotate/")
    page.goto(f"{live_server.url}/exercises/{exercise.pk}/")
    # Nothing is built from the old recording's key-pose frames: version 1 stays in use until the
    # therapist confirms the key poses suggested from the new recording.
    notice = page.inner_text("#confirm-key-poses")
    assert "model version 1 stays in use" in notice, notice
    exercise.refresh_from_db()
    assert exercise.models.count() == 1 and exercise.active_model.version == 1
    suggested = page.evaluate(
        f"async () => (await fetch('{live_server.url}/exercises/{exercise.pk}/tutor.json')).json()"
    )
    page.goto(f"{live_server.url}/exercises/{exercise.pk}/annotate/")
    page.wait_for_selector("#annotate[data-ready='1']", state="attached")
    page.click("#save-landmarks")
    page.wait_for_function(
        "document.getElementById('landmarks-status').textContent"
        ".startsWith('Saved. Model version 2')"
    )
    exercise.refresh_from_db()
    assert exercise.models.count() == 2 and exercise.active_model.version == 2
    assert exercise.tutor_landmark_frames == list(suggested["suggested_frames"]) != old_frames
    page.goto(f"{live_server.url}/exercises/{exercise.pk}/")
    assert "model version 2 (in use)" in page.inner_text("#training-report")
    assert page.locator("#confirm-key-poses").count() == 0

    after = result(page, live_server.url, recording)
    assert after["model_version"] == 1
    assert after["metrics"]["score"] == before["metrics"]["score"]
    page.goto(f"{live_server.url}/recordings/{recording.pk}/")
    page.wait_for_load_state("networkidle")

    # A rule picked from lists appears in the rules' text.
    page.goto(f"{live_server.url}/exercises/{exercise.pk}/annotate/")
    page.select_option("#id_part", label="left lower leg")
    page.select_option("#id_direction", "away")
    page.fill("#id_degrees", "25")
    page.select_option("#id_moment", "2")
    page.fill("#id_sentence", "Bend your left knee further")
    page.click("#add-rule")
    page.wait_for_selector("#grammar")
    text = page.input_value("#grammar")
    assert (
        'type$2 & (@left_lower_leg$3 | @left_lower_leg$4) -> F:"Bend your left knee further"'
        in text
    )
    page.wait_for_function(
        "document.getElementById('grammar-status').textContent.startsWith('Valid')"
    )
    assert errors == [], errors
