import pytest
from django.core.management import call_command
from django.core.management.base import CommandError

from webapp.accounts.models import Clinic, User
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient


@pytest.mark.django_db
def test_demo_clinic_loads_once():
    call_command("load_demo")
    call_command("load_demo")
    assert Clinic.objects.filter(name="Demo clinic").count() == 1
    assert User.objects.filter(username__startswith="demo-").count() == 2
    assert Patient.objects.count() == 1
    exercises = Exercise.objects.all()
    assert exercises.count() == 3
    for exercise in exercises:
        assert exercise.tutor_file.size > 10_000
        assert exercise.tutor_landmark_types[0] == 1
        assert len(exercise.tutor_landmark_frames) == len(exercise.tutor_landmark_types)


@pytest.mark.django_db
def test_demo_passwords_work(client):
    call_command("load_demo")
    assert client.login(username="demo-therapist", password="demo-therapist-pw")
    assert client.login(username="demo-patient", password="demo-patient-pw")


@pytest.mark.django_db
def test_demo_refused_in_production(settings):
    settings.DEMO_ALLOWED = False
    with pytest.raises(CommandError):
        call_command("load_demo")
    assert not User.objects.filter(username="demo-therapist").exists()
