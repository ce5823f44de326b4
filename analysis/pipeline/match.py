"""Does the recording show the exercise at all? The stage that turns a mismatch into a result.

A shoulder abduction uploaded as a deep squat must not be scored as a bad squat: the pipeline
says "This recording does not look like a deep squat" instead, counts no repetition and gives no
score, and names the exercise it does look like when the caller passed the clinic's other
exercises (`Candidate`, plain data: an id, a name and the tutor's retrieval features). The
exercise's name is the caller's (`MatchContext`); the model file does not carry it.

The evidence, each measured against the tutor (thresholds in `MatchOptions`, chosen on UI-PRMD
with the sessions of the right exercise, correct and incorrect, far inside them; see
`bench/eval_mismatch.py` and docs/EVALUATION.md):

- repetitions: none found along the exercise's progress axis;
- stillness: the recording's 5–95 % span on the exercise's progress axis against the tutor's,
  and the movement of the exercise's own joints against the tutor's, both tiny;
- which joints move: the cosine between the recording's and the tutor's per-joint movement
  amplitudes (different body parts move);
- the clinic's other exercises: paper 002's DTW distance (17 body-part distances, 15 fps) from
  the recording to every tutor; another exercise much nearer than this one's tutor.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from analysis.bvh import AnalysisInputError, Motion
from analysis.kinematics import Kinematics
from analysis.pipeline.model import FittedModel
from analysis.pipeline.results import ExerciseMatch
from analysis.pipeline.tutor_parts import RETRIEVAL_FPS, amplitudes, features_of
from analysis.retrieval import MotionRetriever

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Candidate:
    """Another exercise of the clinic: its id, its name and its tutor's retrieval features
    ((F, 17) body-part distances at 15 fps, `analysis.retrieval.recording_features`)."""

    id: str
    name: str
    features: FloatArray


@dataclass(frozen=True)
class MatchContext:
    """What the caller knows and the model does not: the exercise's name and the others."""

    exercise_name: str = "this exercise"
    candidates: Sequence[Candidate] = field(default_factory=tuple)


@dataclass(frozen=True)
class MatchOptions:
    """Below ``min_progress`` of the tutor's span on its progress axis and below
    ``min_own_motion`` of the tutor's movement in the exercise's joints (both: a patient with a
    small range still does the exercise; UI-PRMD's incorrect sessions reach 0.35 and 0.5),
    below ``min_profile`` cosine between per-joint movement amplitudes, or another exercise's
    tutor ``margin`` times nearer than this one's: the recording does not fit."""

    min_progress: float = 0.25
    min_profile: float = 0.6
    min_own_motion: float = 0.3
    margin: float = 1.75


def span(signal: FloatArray) -> float:
    return float(np.percentile(signal, 95) - np.percentile(signal, 5))


@dataclass(frozen=True)
class Evidence:
    """The figures the decision reads (ratios to the tutor; ``nearer``: own distance over the
    nearest other exercise's, None without candidates) and the nearest candidate."""

    repetitions: int
    progress: float
    profile: float
    own_motion: float
    nearer: float | None = None
    nearest: Candidate | None = None


def movement_evidence(
    points: FloatArray, progress: FloatArray, repetitions: int, model: FittedModel
) -> Evidence:
    """``points``: the recording's (F, J, 3) scaled positions (mirrored as scored);
    ``progress``: its progress signal; both as the pipeline prepared them."""
    parts = model.components
    tutor = model.tutor_parts.amplitudes
    mine = amplitudes(points)
    own = parts.involved_index
    profile = float(mine[1:] @ tutor[1:] / (np.linalg.norm(mine[1:]) * np.linalg.norm(tutor[1:])))
    return Evidence(
        repetitions=repetitions,
        progress=span(progress) / max(span(parts.papers.tutor_progress), 1e-9),
        profile=profile if np.isfinite(profile) else 0.0,
        own_motion=float(mine[own].sum() / max(float(tutor[own].sum()), 1e-9)),
    )


def nearest_other(
    motion: Motion, model: FittedModel, candidates: Sequence[Candidate], kin: Kinematics
) -> tuple[float | None, Candidate | None]:
    """Own tutor's DTW distance over the nearest candidate's, and that candidate (None, None
    without candidates or when a take's body parts cannot be found); ``kin``: the motion's
    kinematics."""
    tutor = model.tutor_parts.features
    if not candidates or tutor.size == 0:
        return None, None
    try:
        mine = features_of(motion, kin)
    except (AnalysisInputError, ValueError):
        return None, None
    known = [c for c in candidates if c.features.ndim == 2 and c.features.shape[1] == mine.shape[1]]
    if not known:
        return None, None
    library = [tutor, *(np.asarray(c.features, dtype=np.float64) for c in known)]
    n = min(6, mine.shape[1])
    retriever = MotionRetriever(n_components=n, frame_rate=RETRIEVAL_FPS, metric="features")
    distances = retriever.fit(library, list(range(len(library)))).distances(mine)
    best = 1 + int(np.argmin(distances[1:]))
    return float(distances[0] / max(float(distances[best]), 1e-12)), known[best - 1]


def decide(evidence: Evidence, context: MatchContext, options: MatchOptions) -> ExerciseMatch:
    """The verdict and its plain words (see the module docstring)."""
    name = context.exercise_name
    nearer = evidence.nearer is not None and evidence.nearer > options.margin
    looks_like = evidence.nearest if evidence.nearer is not None and evidence.nearer > 1 else None
    if evidence.repetitions == 0:
        reason = f"we found no repetition of {name} in it"
    elif evidence.progress < options.min_progress and evidence.own_motion < options.min_own_motion:
        reason = f"the body parts that move in {name} hardly move in it"
    elif evidence.profile < options.min_profile:
        reason = f"other body parts move in it than in {name}"
    elif nearer:
        reason = f"it is much closer to another exercise of the clinic than to {name}"
    else:
        return ExerciseMatch()
    also = f" It looks more like {looks_like.name}." if looks_like is not None else ""
    message = (
        f"This recording does not look like {name}: {reason}.{also} Check that the right "
        "exercise was chosen; moving the recording to its exercise analyses it again."
    )
    return ExerciseMatch(False, message, looks_like.id if looks_like is not None else None)


def check_fit(  # noqa: PLR0917 (the pipeline's own figures, passed as they are)
    seen: tuple[Motion, Kinematics],
    points: FloatArray,
    progress: FloatArray,
    repetitions: int,
    model: FittedModel,
    context: MatchContext | None = None,
    options: MatchOptions | None = None,
) -> ExerciseMatch:
    """Whether the recording (``seen``: its motion on the model's skeleton and frame rate and
    that motion's kinematics; ``points`` and ``progress`` as prepared, ``repetitions`` found)
    fits the model's exercise."""
    context = context or MatchContext()
    evidence = movement_evidence(points, progress, repetitions, model)
    motion, kin = seen
    nearer, nearest = nearest_other(motion, model, context.candidates, kin)
    evidence = Evidence(**{**evidence.__dict__, "nearer": nearer, "nearest": nearest})
    return decide(evidence, context, options or MatchOptions())
