import pytest
from django.core.management import call_command
from django.core.management.base import CommandError

from webapp.accounts.models import Clinic, User
from webapp.exercises.body_parts import ticked
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient


@pytest.mark.django_db
def test_demo_clinic_loads_once(client, settings):
    settings.DEMO_ALLOWED = True  # as `make demo` sets it
    call_command("load_demo")
    call_command("load_demo")  # idempotent: nothing created or analysed twice
    assert Clinic.objects.filter(name="Demo clinic").count() == 1
    assert User.objects.filter(username__startswith="demo-").count() == 3
    assert Patient.objects.count() == 2
    exercises = Exercise.objects.all()
    assert exercises.count() == 3
    for exercise in exercises:
        assert exercise.tutor_file.size > 10_000
        assert exercise.tutor_landmark_types[0] == 1
        assert len(exercise.tutor_landmark_frames) == len(exercise.tutor_landmark_types)
    assert_analysed_recordings_and_models()
    assert_body_parts_ticked_and_described(client)
    # The published demo passwords work (one load is slow enough: the same test checks them).
    assert client.login(username="demo-therapist", password="demo-therapist-pw")
    assert client.login(username="demo-patient", password="demo-patient-pw")
    assert client.login(username="demo-admin", password="demo-admin-pw")


@pytest.mark.django_db
def test_demo_refused_in_production(settings):
    settings.DEMO_ALLOWED = False
    with pytest.raises(CommandError, match="DEMO_ALLOWED=1"):
        call_command("load_demo")
    assert not User.objects.filter(username="demo-therapist").exists()


def test_the_demo_loader_is_off_unless_switched_on_whatever_debug_says(tmp_path):
    """DEMO_ALLOWED, not DEBUG, lets the loader run: off by default with DEBUG on or off."""
    import subprocess
    import sys

    show = "import django; django.setup(); from django.conf import settings as s; "
    show += "print(s.DEMO_ALLOWED)"
    base = {
        "PATH": "/usr/bin:/bin",
        "DJANGO_SETTINGS_MODULE": "webapp.settings",
        "DATA_DIR": str(tmp_path),
        "SECRET_KEY": "a-test-key-that-is-not-the-development-one",
    }
    answers = [
        subprocess.run([sys.executable, "-c", show], env={**base, **extra}, capture_output=True,
                       text=True, check=True).stdout.split()[-1]
        for extra in ({"DEBUG": "1"}, {"DEBUG": "0"}, {"DEBUG": "0", "DEMO_ALLOWED": "1"})
    ]  # fmt: skip
    assert answers == ["False", "False", "True"]


def assert_analysed_recordings_and_models():
    from webapp.recordings.models import AnalysisRun, Recording

    for exercise in Exercise.objects.all():
        assert exercise.active_model is not None and exercise.active_model.version == 1
    assert Recording.objects.count() == 6
    runs = AnalysisRun.objects.all()
    assert runs.count() == 6
    assert {run.status for run in runs} == {"succeeded"}
    assert all(run.summary["repetitions"] for run in runs)
    for patient in Patient.objects.all():
        assert patient.recordings.count() >= 2 and patient.last_activity_at is not None
        assert patient.prescriptions.exists() and patient.levels.exists()


def assert_body_parts_ticked_and_described(client):
    """Each demo exercise's page ticks the body parts its model trains; the shoulder abduction
    says to go above shoulder height, as its reference (about 140°) does."""
    assert client.login(username="demo-therapist", password="demo-therapist-pw")
    for exercise in Exercise.objects.all():
        shown = client.get(f"/exercises/{exercise.pk}/tutor.json").json()["involved_joints"]
        trained = set(exercise.active_model.training_report.get("involved_joints") or [])
        assert len(shown) >= 3, exercise.name
        assert shown == ticked(exercise.tutor_motion().skeleton, trained), exercise.name
    abduction = Exercise.objects.get(name="Shoulder abduction")
    page = client.get(f"/exercises/{abduction.pk}/").content.decode()
    assert "past shoulder height" in page and "to shoulder height and" not in page
    client.logout()


@pytest.mark.django_db
def test_a_published_demo_password_gets_the_full_work_factor_at_its_first_sign_in(settings):
    """The loader hashes the published passwords with few rounds (seconds off `make run`); the
    first sign-in hashes the password again with the site's own rounds."""
    from django.contrib.auth.hashers import PBKDF2PasswordHasher

    from webapp.accounts.models import Role
    from webapp.demo.clinic import PUBLISHED_PASSWORD_ROUNDS, ensure_user

    settings.PASSWORD_HASHERS = ["django.contrib.auth.hashers.PBKDF2PasswordHasher"]
    clinic = Clinic.objects.create(name="Demo clinic")
    user = ensure_user("demo-x", "published-pw", clinic, Role.THERAPIST, "Dee Example")
    assert user.password.split("$")[1] == str(PUBLISHED_PASSWORD_ROUNDS)
    assert not user.check_password("another-pw")
    assert user.check_password("published-pw")  # signing in: Django hashes it again
    user.refresh_from_db()
    assert user.password.split("$")[1] == str(PBKDF2PasswordHasher.iterations)
    assert user.check_password("published-pw")
