"""A therapist starts the tutor's key poses from the system's suggestion and saves them."""

from __future__ import annotations

import pytest

from tests.personas import PASSWORD, make_exercise, make_user

pytestmark = pytest.mark.e2e


@pytest.fixture
def therapist_and_exercise(transactional_db, settings, tmp_path):
    from webapp.accounts.models import Clinic, Role

    settings.MEDIA_ROOT = tmp_path / "media"
    settings.PASSWORD_HASHERS = ["django.contrib.auth.hashers.MD5PasswordHasher"]
    clinic = Clinic.objects.create(name="Annotating clinic")
    user = make_user("annotator", clinic, Role.THERAPIST)
    exercise = make_exercise(clinic)
    exercise.tutor_landmark_frames, exercise.tutor_landmark_types = [], []
    exercise.save()
    return user, exercise


def test_suggested_key_poses_are_drawn_accepted_and_saved(
    page, live_server, therapist_and_exercise
):
    user, exercise = therapist_and_exercise
    page.goto(f"{live_server.url}/accounts/login/")
    page.fill("#id_username", user.username)
    page.fill("#id_password", PASSWORD)
    page.click("button[type=submit]")
    page.wait_for_url(lambda url: "/accounts/login" not in url)

    page.goto(f"{live_server.url}/exercises/{exercise.pk}/annotate/")
    page.wait_for_selector("#curves line.suggested", state="attached")
    assert page.locator("#curves line.suggested").count() == 3
    page.click("#use-suggestions")
    page.wait_for_function("document.querySelectorAll('#curves line[data-index]').length === 3")
    page.click("#save-landmarks")
    page.wait_for_function("document.getElementById('landmarks-status').textContent === 'Saved.'")

    exercise.refresh_from_db()
    assert exercise.tutor_landmark_types == [1, 2, 1]
    assert abs(exercise.tutor_landmark_frames[1] - 41) <= 5
