"""The demo clinic: a therapist, a clinic admin, two patients (one with an account), three exercises
with UI-PRMD tutors and their models, and a few UI-PRMD recordings per patient with their analyses
(made here or by a worker: `webapp.demo.recordings`).

Idempotent: loading twice keeps existing rows and never duplicates them.
"""

from __future__ import annotations

import csv
import gzip
import hashlib
from dataclasses import dataclass
from pathlib import Path

from django.conf import settings
from django.contrib.auth.hashers import PBKDF2PasswordHasher, get_hasher, make_password
from django.core.files.base import ContentFile
from django.db import transaction

from analysis.bvh import read
from analysis.pipeline.model_fit import moving_joints
from webapp.accounts.models import Clinic, Role, User
from webapp.demo.recordings import DemoRecording, load_recordings
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient

DEMO_CLINIC = "Demo clinic"
UI_PRMD = Path(settings.BASE_DIR) / "data" / "ui-prmd"
LANDMARK_TYPE_NAMES = {"1": "start", "2": "end of range"}


@dataclass(frozen=True)
class DemoExercise:
    code: str
    name: str
    description: str


DEMO_EXERCISES = (
    DemoExercise("m01", "Deep squat", "Overhead deep squat holding a dowel; heels stay down."),
    DemoExercise("m05", "Sit to stand", "Stand up from a chair and sit down again, arms crossed."),
    # The reference raises the arm to about 140° (well above the shoulder): the description says
    # so, or a patient who stops at shoulder height is told to go about 60° higher.
    DemoExercise(
        "m07",
        "Shoulder abduction",
        "Raise the arm out to the side, up past shoulder height as far as is comfortable, "
        "and lower it slowly.",
    ),
)


# Other subjects than the tutors' (s01), so the demo compares two people, as a clinic would.
PAT_RECORDINGS = (
    DemoRecording("Deep squat", "sessions/m01_s02_incorrect.bvh.gz", 20, pain_score=4),
    DemoRecording("Deep squat", "sessions/m01_s03_incorrect.bvh.gz", 12, pain_score=3),
    DemoRecording("Deep squat", "sessions/m01_s02_correct.bvh.gz", 3, pain_score=1),
    DemoRecording("Shoulder abduction", "sessions/m07_s02_correct.bvh.gz", 5),
)
ROBIN_RECORDINGS = (
    DemoRecording("Sit to stand", "sessions/m05_s03_incorrect.bvh.gz", 15, pain_score=5),
    DemoRecording("Sit to stand", "sessions/m05_s03_correct.bvh.gz", 2, pain_score=2),
)


def tutor_landmarks(relative_file: str) -> tuple[list[int], list[int]]:
    """Key-pose frames and types of a UI-PRMD file from ``landmarks.csv``."""
    with open(UI_PRMD / "landmarks.csv", newline="") as handle:
        for row in csv.DictReader(handle):
            if row["file"] == relative_file:
                frames = [int(v) for v in row["frames"].split(";")]
                types = [int(v) for v in row["types"].split(";")]
                return frames, types
    raise LookupError(f"no landmarks for {relative_file}")


def ensure_user(username: str, password: str, clinic: Clinic, role: str, name: str) -> User:
    user, created = User.objects.get_or_create(
        username=username, defaults={"clinic": clinic, "role": role}
    )
    if created:
        first, _, last = name.partition(" ")
        user.first_name, user.last_name = first, last
        user.password = published_password_hash(password)
        user.save()
    return user


# A published password's hash protects nothing: hashed with few rounds, it costs the loader (and
# so `make run`'s first page) nothing, not a second or more each; Django hashes it again with its
# full work factor when the account first signs in (the hasher's `must_update`).
PUBLISHED_PASSWORD_ROUNDS = 1000


def published_password_hash(password: str) -> str:
    hasher = get_hasher()
    if not isinstance(hasher, PBKDF2PasswordHasher):  # a site with another hasher: its own way
        return make_password(password)
    return hasher.encode(password, hasher.salt(), iterations=PUBLISHED_PASSWORD_ROUNDS)


def ensure_exercise(clinic: Clinic, spec: DemoExercise) -> Exercise:
    existing = Exercise.objects.filter(clinic=clinic, name=spec.name).first()
    if existing is not None:
        return existing
    relative = f"sessions/{spec.code}_s01_correct.bvh.gz"
    content = (UI_PRMD / relative).read_bytes()
    frames, types = tutor_landmarks(relative)
    # The body parts the model trains are ticked on the exercise page, as a therapist would tick
    # them: those that move between the reference's key poses (what the build picks unticked).
    involved = moving_joints(read(gzip.decompress(content)), frames, types)
    exercise = Exercise(
        clinic=clinic,
        name=spec.name,
        description=spec.description,
        tutor_checksum=hashlib.sha256(content).hexdigest(),
        tutor_landmark_frames=frames,
        tutor_landmark_types=types,
        landmark_type_names=LANDMARK_TYPE_NAMES,
        involved_joints=involved,
    )
    exercise.tutor_file.save(f"{spec.code}_tutor.bvh.gz", ContentFile(content), save=False)
    exercise.save()
    return exercise


# (username, password): published, so the loader runs only where DEMO_ALLOWED says so.
DEMO_ACCOUNTS = (
    ("demo-therapist", "demo-therapist-pw"),
    ("demo-patient", "demo-patient-pw"),
    ("demo-admin", "demo-admin-pw"),
)


@transaction.atomic
def load_demo_clinic(*, analyse_here: bool = True) -> Clinic:
    """The demo clinic's rows and files; its analyses run here (``analyse_here``) or are left
    to a worker (enqueued when this transaction commits: `webapp.demo.recordings`)."""
    clinic, _ = Clinic.objects.get_or_create(name=DEMO_CLINIC)
    (therapist_name, therapist_pw), (patient_name, patient_pw), (admin_name, admin_pw) = (
        DEMO_ACCOUNTS
    )
    therapist = ensure_user(therapist_name, therapist_pw, clinic, Role.THERAPIST, "Dana Therapist")
    # The clinic admin reads the audit log and manages every token of the clinic.
    ensure_user(admin_name, admin_pw, clinic, Role.CLINIC_ADMIN, "Alex Admin")
    patient_user = ensure_user(patient_name, patient_pw, clinic, Role.PATIENT, "Pat Patient")
    patient, _ = Patient.objects.get_or_create(
        clinic=clinic, user=patient_user, defaults={"display_name": "Pat Patient"}
    )
    patient.therapists.add(therapist)
    second, _ = Patient.objects.get_or_create(
        clinic=clinic, display_name="Robin Second", defaults={"notes": "Knee rehabilitation."}
    )
    second.therapists.add(therapist)
    exercises = {spec.name: ensure_exercise(clinic, spec) for spec in DEMO_EXERCISES}
    plan = {patient: PAT_RECORDINGS, second: ROBIN_RECORDINGS}
    # positional: tests replace load_recordings with `lambda *args: None`
    load_recordings(UI_PRMD, plan, exercises, therapist, analyse_here)
    return clinic
