"""Paper 002 retrieval in the clinic: recognise the exercise of an upload and find the most
similar earlier recordings.

Every recording (and every exercise's tutor) is turned into its (F', 17) body-part distance
features at 15 fps once; the features are cached by file checksum, since parsing a BVH costs about
0.1 s. A small `MotionRetriever` (PCA + 2-bit codes + DTW over a lookup table) is fitted per
question on the few candidates the question concerns, which takes milliseconds.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from django.conf import settings
from django.core.cache import cache

from analysis.bvh import Motion, read
from analysis.kinematics import positions
from analysis.retrieval import MotionRetriever, recording_features
from webapp.accounts.models import User
from webapp.exercises.models import Exercise
from webapp.recordings.models import Recording

FRAME_RATE = 15.0
CACHE_SECONDS = 7 * 24 * 3600


@dataclass(frozen=True)
class Guess:
    exercise: Exercise
    distance: float


def motion_features(motion: Motion) -> np.ndarray:
    """(F, 17) float32 retrieval features of a parsed recording at 15 fps."""
    world = positions(motion)
    return recording_features(world, motion.skeleton.names, motion.fps, target_fps=FRAME_RATE)


def file_features(field, checksum: str) -> np.ndarray:
    key = f"retrieval-features:{checksum or field.name}"
    cached = cache.get(key)
    if cached is None:
        with field.open("rb") as handle:
            cached = motion_features(read(handle.read())).astype(np.float32)
        cache.set(key, cached, CACHE_SECONDS)
    return cached


def exercise_features(exercise: Exercise) -> np.ndarray:
    name = exercise.tutor_file.name.encode()
    checksum = exercise.tutor_checksum or hashlib.sha256(name).hexdigest()
    return file_features(exercise.tutor_file, f"tutor-{exercise.pk}-{checksum}")


def fitted(features: list[np.ndarray], labels: list[Any]) -> MotionRetriever:
    n_components = min(settings.RETRIEVAL_COMPONENTS, features[0].shape[1])
    return MotionRetriever(n_components=n_components, frame_rate=FRAME_RATE).fit(features, labels)


def labelled_examples(candidates: list[Exercise]) -> list[tuple[Exercise | Recording, str]]:
    """Each candidate's tutor, then their newest confirmed recordings, with its exercise id."""
    examples: list[tuple[Exercise | Recording, str]] = [(e, str(e.pk)) for e in candidates]
    confirmed = Recording.objects.filter(exercise__in=candidates).order_by("-uploaded_at")
    examples += [(r, str(r.exercise_id)) for r in confirmed[: settings.RETRIEVAL_MAX_CANDIDATES]]
    return examples


def example_features(example: Exercise | Recording) -> np.ndarray:
    if isinstance(example, Exercise):
        return exercise_features(example)
    return file_features(example.file, example.checksum)


def identify_exercise(
    motion: Motion, exercises, progress: Callable[[float], None] | None = None
) -> Guess | None:
    """The clinic exercise whose tutor or confirmed recordings are nearest (1-NN), or None.

    `progress(fraction)` hears how far the reading of the examples' features is (0..1): on a
    cold cache that is nearly all the time this takes."""
    candidates = list(exercises.filter(archived_at__isnull=True))
    if not candidates:
        return None
    examples = labelled_examples(candidates)
    features: list[np.ndarray] = []
    labels: list[Any] = []
    for done, (example, label) in enumerate(examples, start=1):
        features.append(example_features(example))
        labels.append(label)
        if progress is not None:
            progress(done / len(examples))
    retriever = fitted(features, labels)
    index, distance = retriever.most_similar(motion_features(motion), k=1)[0]
    by_id = {str(e.pk): e for e in candidates}
    return Guess(by_id[labels[index]], distance)


def comparable_recordings(recording: Recording, user: User):
    """Earlier recordings of the same exercise the user may see (a patient: only their own)."""
    earlier = Recording.objects.filter(
        clinic_id=recording.clinic_id,
        exercise_id=recording.exercise_id,
        uploaded_at__lt=recording.uploaded_at,
    ).select_related("patient")
    if not user.is_staff_member:
        earlier = earlier.filter(patient_id=recording.patient_id)
    return list(earlier.order_by("-uploaded_at")[: settings.RETRIEVAL_MAX_CANDIDATES])


def most_similar(recording: Recording, user: User, k: int = 5) -> list[dict[str, Any]]:
    """The k earlier recordings nearest to this one (paper 002 DTW distance), nearest first."""
    if recording.exercise_id is None:
        return []
    earlier = comparable_recordings(recording, user)
    if not earlier:
        return []
    features = [file_features(r.file, r.checksum) for r in earlier]
    retriever = fitted(features, [str(r.pk) for r in earlier])
    query = file_features(recording.file, recording.checksum)
    return [
        {
            "recording": str(earlier[index].pk),
            "patient": str(earlier[index].patient_id),
            "patient_name": earlier[index].patient.display_name,
            "uploaded_at": earlier[index].uploaded_at.isoformat(),
            "distance": round(distance, 4),
        }
        for index, distance in retriever.most_similar(query, k=k)
    ]
