"""The demo clinic's analysed recordings: UI-PRMD sessions analysed in this process at load time.

Each exercise's model is built once (about a second each); each recording is stored with one
analysis run that is analysed directly, without the task queue, so a fresh `make run` shows
results even before a worker is started. Recordings are matched by checksum: loading twice adds
nothing.
"""

from __future__ import annotations

import datetime
import hashlib
from dataclasses import dataclass
from pathlib import Path

from django.core.files.base import ContentFile
from django.utils import timezone

from analysis.bvh import read
from webapp.accounts.models import User
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient, Prescription
from webapp.recordings.models import AnalysisRun, Recording
from workers import analysis_task, exercise_models


@dataclass(frozen=True)
class DemoRecording:
    exercise: str  # demo exercise name
    file: str  # relative to data/ui-prmd
    days_ago: int
    pain_score: int | None = None


def ensure_recording(
    root: Path, patient: Patient, exercise: Exercise, spec: DemoRecording, user: User
) -> Recording:
    content = (root / spec.file).read_bytes()
    checksum = hashlib.sha256(content).hexdigest()
    existing = Recording.objects.filter(patient=patient, checksum=checksum).first()
    if existing is not None:
        return existing
    motion = read(content)
    n_frames = motion.frames.shape[0]
    recording = Recording(
        clinic=patient.clinic,
        patient=patient,
        exercise=exercise,
        checksum=checksum,
        original_name=Path(spec.file).name,
        size_bytes=len(content),
        n_frames=n_frames,
        n_joints=len(motion.skeleton.names),
        fps=motion.fps,
        duration_s=n_frames * motion.frame_time,
        pain_score=spec.pain_score,
        uploaded_by=user,
    )
    recording.file.save(f"{recording.pk}.bvh.gz", ContentFile(content), save=False)
    recording.save()
    when = timezone.now() - datetime.timedelta(days=spec.days_ago)
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when)
    run = AnalysisRun.objects.create(recording=recording)
    analysis_task.analyse_run(str(run.pk))
    Patient.objects.filter(pk=patient.pk, last_activity_at__isnull=True).update(
        last_activity_at=when
    )
    Patient.objects.filter(pk=patient.pk, last_activity_at__lt=when).update(last_activity_at=when)
    return recording


def ensure_prescription(patient: Patient, exercise: Exercise, weeks_ago: int) -> None:
    start = timezone.localdate() - datetime.timedelta(weeks=weeks_ago)
    Prescription.objects.get_or_create(
        patient=patient,
        exercise=exercise,
        defaults={"start_date": start, "sessions_per_week": 3, "target_repetitions": 10},
    )


def load_recordings(
    root: Path,
    plan: dict[Patient, tuple[DemoRecording, ...]],
    exercises: dict[str, Exercise],
    user: User,
) -> None:
    for exercise in exercises.values():
        exercise_models.active_model(exercise)  # builds version 1 the first time
    for patient, specs in plan.items():
        for spec in specs:
            exercise = exercises[spec.exercise]
            ensure_prescription(patient, exercise, weeks_ago=4)
            ensure_recording(root, patient, exercise, spec, user)
