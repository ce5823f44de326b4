"""People the web tests act as: a therapist, a colleague in the same clinic, an outsider from
another clinic, the patient, another patient of the same clinic, the clinic's admin, and
anonymous."""

from __future__ import annotations

import csv
import hashlib
from dataclasses import dataclass
from pathlib import Path

from webapp.accounts.models import Clinic, Role, User
from webapp.patients.models import Patient

PASSWORD = "a-long-test-password-42"


@dataclass(frozen=True)
class World:
    clinic: Clinic
    other_clinic: Clinic
    therapist: User
    colleague: User
    outsider: User
    patient_user: User
    other_patient_user: User
    patient: Patient
    other_patient: Patient
    outsider_patient: Patient
    clinic_admin: User


def make_user(username: str, clinic: Clinic, role: str) -> User:
    user = User(username=username, clinic=clinic, role=role)
    user.set_password(PASSWORD)
    user.save()
    return user


def make_world() -> World:
    clinic = Clinic.objects.create(name="North clinic")
    other = Clinic.objects.create(name="South clinic")
    therapist = make_user("therapist", clinic, Role.THERAPIST)
    colleague = make_user("colleague", clinic, Role.THERAPIST)
    outsider = make_user("outsider", other, Role.THERAPIST)
    patient_user = make_user("patient", clinic, Role.PATIENT)
    other_patient_user = make_user("other-patient", clinic, Role.PATIENT)
    patient = Patient.objects.create(clinic=clinic, user=patient_user, display_name="Ann Example")
    patient.therapists.add(therapist)
    other_patient = Patient.objects.create(
        clinic=clinic, user=other_patient_user, display_name="Bob Example"
    )
    outsider_patient = Patient.objects.create(clinic=other, display_name="Cy Elsewhere")
    clinic_admin = make_user("clinic-admin", clinic, Role.CLINIC_ADMIN)
    return World(
        clinic,
        other,
        therapist,
        colleague,
        outsider,
        patient_user,
        other_patient_user,
        patient,
        other_patient,
        outsider_patient,
        clinic_admin,
    )


FIXTURES = Path(__file__).resolve().parents[1] / "data" / "ui-prmd"


def fixture_bytes(relative: str) -> bytes:
    return (FIXTURES / relative).read_bytes()


def fixture_landmarks(relative: str) -> tuple[list[int], list[int]]:
    """The annotated landmark frames and types of a UI-PRMD file (data/ui-prmd/landmarks.csv)."""
    with (FIXTURES / "landmarks.csv").open(newline="") as handle:
        for row in csv.DictReader(handle):
            if row["file"] == relative:
                frames = [int(v) for v in row["frames"].split(";")]
                return frames, [int(v) for v in row["types"].split(";")]
    raise KeyError(relative)


def make_exercise(
    clinic: Clinic, name: str = "Deep squat", source: str = "reps/m01_s01_e01.bvh.gz"
):
    from django.core.files.base import ContentFile

    from webapp.exercises.models import Exercise

    frames, types = fixture_landmarks(source)
    exercise = Exercise(
        clinic=clinic,
        name=name,
        tutor_landmark_frames=frames,
        tutor_landmark_types=types,
        landmark_type_names={"1": "start", "2": "end of range"},
    )
    exercise.tutor_file.save("tutor.bvh.gz", ContentFile(fixture_bytes(source)), save=False)
    exercise.save()
    return exercise


def make_recording(patient: Patient, exercise, source: str = "reps/m01_s01_e02.bvh.gz"):
    from django.core.files.base import ContentFile

    from webapp.recordings.models import AnalysisRun, Recording

    content = fixture_bytes(source)
    recording = Recording(
        clinic=patient.clinic,
        patient=patient,
        exercise=exercise,
        checksum=hashlib.sha256(content).hexdigest(),  # reads verify it
    )
    recording.file.save("rec.bvh.gz", ContentFile(content), save=False)
    recording.save()
    AnalysisRun.objects.create(recording=recording)
    return recording
