"""Paper 002 retrieval in the clinic: recognise the exercise of an upload and find the most
similar earlier recordings.

Every recording (and every exercise's tutor) is turned into its (F', 17) body-part distance
features at 15 fps once; the features are cached by file checksum, since parsing a BVH costs about
0.1 s. A small `MotionRetriever` (PCA + 2-bit codes + DTW over a lookup table) is fitted per
question on the few candidates the question concerns, which takes milliseconds.
"""

from __future__ import annotations

import hashlib
import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from django.conf import settings
from django.core.cache import cache

from analysis.bvh import AnalysisInputError, Motion
from analysis.kinematics import positions
from analysis.retrieval import MotionRetriever, recording_features
from analysis.sources import read_recording
from analysis.sources.video import SUFFIXES as VIDEO_SUFFIXES
from webapp.accounts.models import User
from webapp.exercises.models import Exercise
from webapp.recordings.models import AnalysisRun, Recording, RunStatus

log = logging.getLogger(__name__)
FRAME_RATE = 15.0
CACHE_SECONDS = 7 * 24 * 3600
# The newest confirmed takes per exercise the fit check compares with (each costs one DTW; from
# five on, with the reference, the check compares at `MatchOptions.confirmed_margin`).
CONFIRMED_TAKES = 6


@dataclass(frozen=True)
class Guess:
    exercise: Exercise
    distance: float


def motion_features(motion: Motion) -> np.ndarray:
    """(F, 17) float32 retrieval features of a parsed recording at 15 fps."""
    world = positions(motion)
    return recording_features(world, motion.skeleton.names, motion.fps, target_fps=FRAME_RATE)


def _cached_features(key: str, read: Callable[[], Motion]) -> np.ndarray:
    cached = cache.get(key)
    if cached is None:
        cached = motion_features(read()).astype(np.float32)
        cache.set(key, cached, CACHE_SECONDS)
    return cached


def file_features(field, checksum: str) -> np.ndarray | None:
    """A stored recording's features, whatever it was captured with; None for a phone video
    (finding the person in its frames is the worker's long job, not a page's)."""
    if field.name.lower().endswith(VIDEO_SUFFIXES):
        return None

    def read() -> Motion:
        with field.open("rb") as handle:
            return read_recording(field.name, handle.read()).motion

    return _cached_features(f"retrieval-features:{checksum or field.name}", read)


def exercise_features(exercise: Exercise) -> np.ndarray | None:
    """The reference's features; None while a reference video waits for the worker."""
    if not exercise.tutor_ready():
        return None
    name = exercise.tutor_file.name.encode()
    checksum = exercise.tutor_checksum or hashlib.sha256(name).hexdigest()
    return _cached_features(f"retrieval-features:tutor-{exercise.pk}-{checksum}",
                            exercise.tutor_motion)  # fmt: skip


def confirmed(run: AnalysisRun | None) -> bool:
    """Whether a therapist confirmed this run's take as a correct one of its exercise: it is
    the recording's newest run (a moved recording's new run is not yet), it fits its exercise,
    and every repetition it found carries a therapist's "passed"."""
    if run is None or run.status != RunStatus.SUCCEEDED:
        return False
    result = run.result
    found = len(result.repetitions) if result is not None and result.match.fits else 0
    verdicts = dict(run.repetition_labels.filter(index__lt=found).values_list("index", "passed"))
    return found > 0 and len(verdicts) == found and all(verdicts.values())


def confirmed_takes(exercise: Exercise, limit: int = CONFIRMED_TAKES) -> list[np.ndarray]:
    """Retrieval features of the exercise's newest takes a therapist confirmed as correct
    (`confirmed`); phone videos are left out (their features are the worker's long job), and so
    is a take whose file can no longer be read."""
    labelled = (
        Recording.objects.filter(exercise=exercise, runs__repetition_labels__passed=True)
        .distinct()
        .order_by("-uploaded_at")
    )
    takes: list[np.ndarray] = []
    for recording in labelled.iterator():
        if len(takes) >= limit:
            break
        if not confirmed(recording.runs.order_by("-created_at").first()):
            continue
        try:
            found = file_features(recording.file, recording.checksum)
        except (AnalysisInputError, ValueError, OSError):
            log.info("confirmed take %s left out of the fit check", recording.pk, exc_info=True)
            continue
        if found is not None:
            takes.append(found)
    return takes


def fitted(features: list[np.ndarray], labels: list[Any]) -> MotionRetriever:
    n_components = min(settings.RETRIEVAL_COMPONENTS, features[0].shape[1])
    return MotionRetriever(n_components=n_components, frame_rate=FRAME_RATE).fit(features, labels)


def labelled_examples(candidates: list[Exercise]) -> list[tuple[Exercise | Recording, str]]:
    """Each candidate's tutor, then their newest confirmed recordings, with its exercise id."""
    examples: list[tuple[Exercise | Recording, str]] = [(e, str(e.pk)) for e in candidates]
    confirmed = Recording.objects.filter(exercise__in=candidates).order_by("-uploaded_at")
    examples += [(r, str(r.exercise_id)) for r in confirmed[: settings.RETRIEVAL_MAX_CANDIDATES]]
    return examples


def example_features(example: Exercise | Recording) -> np.ndarray | None:
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
        found = example_features(example)
        if found is not None:
            features.append(found)
            labels.append(label)
        if progress is not None:
            progress(done / len(examples))
    if not features:
        return None
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
    query = file_features(recording.file, recording.checksum)
    read = [(r, file_features(r.file, r.checksum)) for r in comparable_recordings(recording, user)]
    earlier = [r for r, found in read if found is not None]
    if query is None or not earlier:
        return []
    retriever = fitted([f for _, f in read if f is not None], [str(r.pk) for r in earlier])
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
