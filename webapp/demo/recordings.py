"""The demo clinic's recordings: UI-PRMD sessions, each stored through the upload service like any
upload (checks, storage, first run, its analysis enqueued after the commit).

Where a worker will take the analyses (`make run`: the worker starts beside the server), the
loader only stores them: the site comes up without waiting for them, the demo's recordings show
as being analysed like any upload, and the first analysis of each exercise builds its model in
the worker. With ``analyse_here`` (no worker will come: `make demo`, the tests) each exercise's
model is built and each run analysed in this process before the loader returns.
Recordings are matched by checksum: loading twice adds nothing.
"""

from __future__ import annotations

import datetime
import hashlib
from dataclasses import dataclass
from pathlib import Path

from django.core.files.uploadedfile import SimpleUploadedFile
from django.db.models import Max
from django.utils import timezone

from webapp.accounts.models import User
from webapp.exercises.models import Exercise
from webapp.exercises.services import build_model_now
from webapp.patients.models import Patient, Prescription
from webapp.recordings.models import Recording
from webapp.recordings.services import analyse_now
from webapp.recordings.uploads import parse_upload, store_recording


@dataclass(frozen=True)
class DemoRecording:
    exercise: str  # demo exercise name
    file: str  # relative to data/ui-prmd
    days_ago: int
    pain_score: int | None = None


def ensure_recording(
    root: Path,
    patient: Patient,
    exercise: Exercise,
    spec: DemoRecording,
    user: User,
    *,
    analyse_here: bool,
) -> Recording:
    content = (root / spec.file).read_bytes()
    checksum = hashlib.sha256(content).hexdigest()
    # A demo recording someone deleted stays deleted when the loader runs again.
    existing = Recording.all_objects.filter(patient=patient, checksum=checksum).first()
    if existing is not None:
        return existing
    parsed = parse_upload(SimpleUploadedFile(Path(spec.file).name, content))
    recording, run = store_recording(
        parsed, patient=patient, exercise=exercise, user=user, pain_score=spec.pain_score
    )
    when = timezone.now() - datetime.timedelta(days=spec.days_ago)
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when)
    if run is not None and analyse_here:
        analyse_now(run)  # the message enqueued at the commit then finds the run taken
    return recording


def ensure_prescription(patient: Patient, exercise: Exercise, weeks_ago: int) -> None:
    start = timezone.localdate() - datetime.timedelta(weeks=weeks_ago)
    Prescription.objects.get_or_create(
        patient=patient,
        exercise=exercise,
        defaults={
            "start_date": start,
            "sessions_per_week": 3,
            "sets": 2,
            "target_repetitions": 10,
            "days": "mon,wed,fri",
            "notes": "Move slowly and stop if it hurts.",
        },
    )


def load_recordings(
    root: Path,
    plan: dict[Patient, tuple[DemoRecording, ...]],
    exercises: dict[str, Exercise],
    user: User,
    analyse_here: bool,
) -> None:
    if analyse_here:
        for exercise in exercises.values():
            build_model_now(exercise)  # builds version 1 the first time
    for patient, specs in plan.items():
        for spec in specs:
            exercise = exercises[spec.exercise]
            ensure_prescription(patient, exercise, weeks_ago=4)
            ensure_recording(root, patient, exercise, spec, user, analyse_here=analyse_here)
        # The demo's history is in the past: the patient was last active at their newest upload.
        newest = patient.recordings.aggregate(at=Max("uploaded_at"))["at"]
        Patient.objects.filter(pk=patient.pk).update(last_activity_at=newest)
