"""What the fit check needs from the clinic (`analysis.pipeline.match`), as plain data: the
exercise's name, and the clinic's other exercises with their tutors' retrieval features (paper
002, cached per tutor file by `webapp.recordings.similar`), so a recording that does not fit its
exercise can name the one it looks like."""

from __future__ import annotations

import logging

import numpy as np
from django.conf import settings

from analysis.bvh import AnalysisInputError
from analysis.pipeline.match import Candidate, MatchContext
from webapp.exercises.models import Exercise
from webapp.recordings.similar import confirmed_takes, exercise_features

log = logging.getLogger(__name__)


def spoken(exercise: Exercise) -> str:
    """How a sentence names the exercise: 'the exercise "Deep squat"'."""
    return f"the exercise \u201c{exercise.name}\u201d"


def match_context(exercise: Exercise, recorder: str | None = None) -> MatchContext:
    """The exercise's name and the clinic's other exercises that have a readable tutor, each with
    its takes a therapist confirmed as correct (`webapp.recordings.similar.confirmed_takes`);
    ``recorder``: the recording's source kind (`analysis.sources.RecordingSource.kind`), to
    say whether it was captured as the exercise's reference was."""
    others = (
        Exercise.objects.filter(clinic_id=exercise.clinic_id, archived_at__isnull=True)
        .exclude(pk=exercise.pk)
        .exclude(tutor_file="")
        .order_by("name")
    )
    candidates = []
    for other in others[: settings.RETRIEVAL_MAX_CANDIDATES]:
        try:
            features = np.asarray(exercise_features(other), dtype=np.float64)
        except (AnalysisInputError, ValueError, OSError):  # that tutor cannot be compared
            log.info("exercise %s left out of the fit check", other.pk, exc_info=True)
            continue
        candidates.append(Candidate(str(other.pk), spoken(other), features, takes_of(other)))
    same = recorder is None or recorder == exercise.tutor_kind()
    return MatchContext(spoken(exercise), tuple(candidates), same, takes_of(exercise))


def takes_of(exercise: Exercise) -> tuple[np.ndarray, ...]:
    """The exercise's confirmed takes, as the check's float64 features."""
    return tuple(np.asarray(t, dtype=np.float64) for t in confirmed_takes(exercise))
