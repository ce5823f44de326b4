"""Enqueueing model builds after the commit (the web app's door to the queue for exercises)."""

from __future__ import annotations

import hashlib

from django.core.files.base import ContentFile
from django.db import transaction

from analysis.bvh import Motion
from analysis.landmarks import suggest_key_poses
from webapp.exercises.models import Exercise, ExerciseModel
from workers.tasks import build_exercise_model


def start_model_build(exercise: Exercise) -> ExerciseModel:
    """A new QUEUED model version, built by a worker once the transaction commits."""
    with transaction.atomic():
        row = ExerciseModel.objects.create_next_version(exercise)
        row_id = str(row.pk)
        transaction.on_commit(lambda: build_exercise_model.delay(row_id))
    return row


def build_model_now(exercise: Exercise) -> ExerciseModel:
    """The exercise's active model version; the first one is built in this process (no queue)."""
    exercise.refresh_from_db(fields=["active_model"])
    if exercise.active_model is None:
        row = ExerciseModel.objects.create_next_version(exercise)
        build_exercise_model.apply(args=[str(row.pk)])
        exercise.refresh_from_db(fields=["active_model"])
        if exercise.active_model is None:
            row.refresh_from_db()
            raise RuntimeError(f"building {exercise} version {row.version} failed: {row.error}")
    return exercise.active_model


def kept_key_poses(exercise: Exercise, motion: Motion) -> tuple[list[int], list[int], bool]:
    """The key poses for a new reference: the marked ones when they fit its length, else the
    ones the system suggests (so a model can be built; the page asks to check them)."""
    frames = list(exercise.tutor_landmark_frames)
    if frames and max(frames) < motion.frames.shape[0]:
        return frames, list(exercise.tutor_landmark_types), True
    suggestion = suggest_key_poses(motion)
    return list(suggestion.frames), list(suggestion.types), False


def replace_reference(exercise: Exercise, content: bytes, motion: Motion) -> ExerciseModel:
    """Store a new reference recording and build a new model version from it.

    The earlier file and model versions stay: analyses keep the version they were made with.
    Until the new version is ready no version is active, so a new analysis never uses a model
    of the old reference (it builds from the new one if it comes first)."""
    checksum = hashlib.sha256(content).hexdigest()
    suffix = ".bvh.gz" if content[:2] == b"\x1f\x8b" else ".bvh"
    frames, types, kept = kept_key_poses(exercise, motion)
    with transaction.atomic():
        exercise.tutor_file.save(f"{exercise.pk}-{checksum[:12]}{suffix}", ContentFile(content))
        exercise.tutor_checksum = checksum
        exercise.tutor_landmark_frames, exercise.tutor_landmark_types = frames, types
        names = set(motion.skeleton.names)
        exercise.involved_joints = [j for j in exercise.involved_joints if j in names]
        if not kept:
            earlier = exercise.landmark_type_names or {}
            exercise.landmark_type_names = {
                str(t): earlier[str(t)] for t in sorted(set(types)) if earlier.get(str(t))
            }
        exercise.active_model = None
        exercise.save()
        return start_model_build(exercise)
