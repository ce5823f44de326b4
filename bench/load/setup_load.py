"""Data for the load run: the demo clinic (real analysed recordings), 1,000 more patients with
20,000 synthetic runs, 50 browsing therapists and 20 uploading therapists with a patient each.

Writes the plan the locustfile reads (usernames, patient and recording ids, files to upload).
Run by run_load.py with DATABASE_URL pointing at the throw-away load database and no REDIS_URL,
so that the demo recordings are analysed in-process before the workers start.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
from pathlib import Path

import django

os.environ.setdefault("DJANGO_SETTINGS_MODULE", "webapp.settings")
django.setup()

from django.conf import settings  # noqa: E402
from django.core.management import call_command  # noqa: E402
from django.test import Client  # noqa: E402

from webapp.accounts.models import Clinic, Role, User  # noqa: E402
from webapp.demo.clinic import DEMO_CLINIC, DEMO_EXERCISES, UI_PRMD  # noqa: E402
from webapp.demo.management.commands.fill_large_clinic import (  # noqa: E402
    THERAPIST_PASSWORD,
)
from webapp.exercises.models import Exercise  # noqa: E402
from webapp.patients.models import Patient  # noqa: E402
from webapp.recordings.models import Recording  # noqa: E402

UPLOADERS = 20
SUBJECTS = range(2, 11)  # s01 is every exercise's tutor


def upload_files(clinic: Clinic) -> list[dict]:
    files = []
    for spec in DEMO_EXERCISES:
        exercise = Exercise.objects.get(clinic=clinic, name=spec.name)
        for subject in SUBJECTS:
            for kind in ("correct", "incorrect"):
                path = UI_PRMD / "sessions" / f"{spec.code}_s{subject:02d}_{kind}.bvh.gz"
                if path.exists():
                    files.append({"file": str(path), "exercise": str(exercise.pk)})
    return files


def session_cookie(user: User) -> str:
    """A signed-in session for `user`, made here so that the load measures browsing, not 50
    simultaneous password hashes (PBKDF2 costs about half a second of CPU per login, on purpose)."""
    client = Client()
    client.force_login(user)
    return client.cookies[settings.SESSION_COOKIE_NAME].value


def api_token(username: str) -> str:
    reply = Client().post(
        "/api/v1/auth/token/", {"username": username, "password": THERAPIST_PASSWORD}
    )
    assert reply.status_code == 200, reply.content
    return reply.json()["token"]


def make_uploaders(clinic: Clinic, files: list[dict]) -> list[dict]:
    password = User(username="x")
    password.set_password(THERAPIST_PASSWORD)
    slots = []
    for index in range(UPLOADERS):
        user = User.objects.create(
            username=f"load-uploader-{index:02d}",
            clinic=clinic,
            role=Role.THERAPIST,
            password=password.password,
        )
        patient = Patient.objects.create(clinic=clinic, display_name=f"Load upload {index:02d}")
        patient.therapists.add(user)
        mine = random.Random(index).sample(files, 6)
        slots.append({"token": api_token(user.username), "patient": str(patient.pk), "files": mine})
    return slots


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plan", default="var/load/plan.json")
    parser.add_argument("--patients", type=int, default=1000)
    parser.add_argument("--runs", type=int, default=20_000)
    args = parser.parse_args()
    assert not settings.REDIS_URL, "run without REDIS_URL: the demo analyses run in-process"
    call_command("load_demo")
    call_command(
        "fill_large_clinic",
        clinic=DEMO_CLINIC,
        into_existing=True,
        patients=args.patients,
        runs=args.runs,
        therapists=50,
    )
    clinic = Clinic.objects.get(name=DEMO_CLINIC)
    therapists = User.objects.filter(clinic=clinic, username__contains="-therapist-")
    patient_ids = list(Patient.objects.filter(clinic=clinic).values_list("pk", flat=True))
    real = Recording.objects.filter(clinic=clinic, runs__status="succeeded", file__isnull=False)
    real = real.exclude(file__startswith="recordings/large/").distinct()
    plan = {
        "password": THERAPIST_PASSWORD,
        "sessions": [session_cookie(u) for u in therapists],
        "patients": [str(pk) for pk in random.Random(0).sample(patient_ids, 300)],
        "patient_pages": math.ceil(len(patient_ids) / 25),
        "recordings": [str(pk) for pk in real.values_list("pk", flat=True)],
        "uploaders": make_uploaders(clinic, upload_files(clinic)),
    }
    Path(args.plan).parent.mkdir(parents=True, exist_ok=True)
    Path(args.plan).write_text(json.dumps(plan, indent=1))
    print(f"plan: {len(plan['sessions'])} therapists, {len(patient_ids)} patients, "
          f"{len(plan['recordings'])} analysed recordings to browse")  # fmt: skip


if __name__ == "__main__":
    main()
