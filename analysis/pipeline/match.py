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
  the recording to every tutor, the nearer of the recording and its mirror image (a lunge led
  with the other leg is the same exercise); another exercise ``margin`` times nearer than this
  one's tutor.

One rule (issue 35): the same distances decide "does not fit" and name what it looks like. The
exercises named are the clinic's exercises this test accepts (within ``margin`` of the nearest)
that are nearer than the chosen one, nearest first: the nearest, and the next one too when it is
as close (squat and sit to stand). So a recording moved to the named exercise passes the distance
test there, and one moved to an exercise the test rejects is told "does not look like" again
(the worker passes the same clinic's exercises whichever of them the recording belongs to).

Confirmed takes: an exercise is represented by its reference and by the takes a therapist confirmed
as correct (``MatchContext.own_takes``, ``Candidate.takes``); the distance to an exercise is the
distance to the nearest of them. One person's reference leaves room for another person's style,
hence the margin; when every exercise compared holds ``MatchOptions.confirmed_takes`` takes, the
styles are covered and the nearest exercise is the one that fits (``confirmed_margin``, 1). On
UI-PRMD with six or seven people's takes per exercise, each session compared without its own
person's takes, a session's own exercise was always the nearest (at most 0.972 of the nearest
other's distance) and every other exercise at least 1.029 times farther than the nearest
(`bench/mismatch_references.py`, set ``others``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt

from analysis.bvh import AnalysisInputError, Motion
from analysis.kinematics import Kinematics
from analysis.pipeline.model import FittedModel
from analysis.pipeline.results import ExerciseMatch
from analysis.pipeline.tutor_parts import RETRIEVAL_FPS, amplitudes, features_of
from analysis.retrieval import MotionRetriever
from analysis.retrieval.features import mirrored_features

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Candidate:
    """Another exercise of the clinic: its id, its name and its tutor's retrieval features
    ((F, 17) body-part distances at 15 fps, `analysis.retrieval.recording_features`);
    ``takes``: the same features of its takes confirmed as correct (module docstring)."""

    id: str
    name: str
    features: FloatArray
    takes: Sequence[FloatArray] = ()

    def references(self) -> list[FloatArray]:
        return [np.asarray(f, dtype=np.float64) for f in (self.features, *self.takes)]


@dataclass(frozen=True)
class MatchContext:
    """What the caller knows and the model does not: the exercise's name and the others."""

    exercise_name: str = "this exercise"
    candidates: Sequence[Candidate] = field(default_factory=tuple)
    # whether the recording was captured as the references were (a phone video against Kinect
    # references is not): distances across recorders carry the skeletons' differences too
    same_recorder: bool = True
    # the exercise's own takes confirmed as correct, besides its reference (retrieval features)
    own_takes: Sequence[FloatArray] = ()

    def fewest_takes(self) -> int:
        """The fewest takes (reference included) of any exercise compared."""
        return 1 + min([len(self.own_takes), *(len(c.takes) for c in self.candidates)])


@dataclass(frozen=True)
class MatchOptions:
    """Below ``min_progress`` of the tutor's span on its progress axis and below
    ``min_own_motion`` of the tutor's movement in the exercise's joints (both: a patient with a
    small range still does the exercise; UI-PRMD's incorrect sessions reach 0.35 and 0.5),
    below ``min_profile`` cosine between per-joint movement amplitudes, or another exercise's
    tutor more than ``margin`` times nearer than this one's: the recording does not fit. On
    UI-PRMD a session's own tutor came at most 1.13 times farther than the nearest of the ten;
    1.3 refuses none of them and most other exercises' sessions (bench/eval_mismatch.py).
    A recording from another kind of recorder than the references (a phone video or the camera
    page against Kinect references) is held to ``cross_recorder_margin``: the side-view squat
    video of tests/analysis/fixtures/capture/ comes 1.33 times (as uploaded) to 1.51 times (as
    the camera page takes it) nearer the Kinect sit-to-stand than the Kinect deep squat.
    When every exercise compared holds at least ``confirmed_takes`` takes (its reference and
    confirmed correct takes), the nearest exercise fits and no other: ``confirmed_margin``."""

    min_progress: float = 0.25
    min_profile: float = 0.6
    min_own_motion: float = 0.3
    margin: float = 1.3
    cross_recorder_margin: float = 1.75
    confirmed_takes: int = 6
    confirmed_margin: float = 1.0

    def margin_for(self, context: MatchContext) -> float:
        if not context.same_recorder:
            return self.cross_recorder_margin
        if context.candidates and context.fewest_takes() >= self.confirmed_takes:
            return self.confirmed_margin
        return self.margin


def span(signal: FloatArray) -> float:
    return float(np.percentile(signal, 95) - np.percentile(signal, 5))


@dataclass(frozen=True)
class Evidence:
    """The figures the decision reads (ratios to the tutor; ``nearer``: own distance over the
    nearest other exercise's, None without candidates), the nearest candidate and ``also`` the
    next nearest when the distance test accepts it too (`Ranking.named`)."""

    repetitions: int
    progress: float
    profile: float
    own_motion: float
    nearer: float | None = None
    nearest: Candidate | None = None
    also: Candidate | None = None


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


@dataclass(frozen=True)
class Ranking:
    """The recording's distance to its own exercise's tutor and to every candidate's, nearest
    candidate first."""

    own: float
    others: tuple[tuple[float, Candidate], ...]

    def nearer(self) -> float:
        """Own distance over the nearest candidate's (above 1: another exercise is nearer)."""
        return self.own / max(self.others[0][0], 1e-12)

    def named(self, margin: float) -> tuple[Candidate, ...]:
        """The candidates the distance test accepts (within ``margin`` of the nearest of all
        the clinic's exercises, this one included) that are nearer than this one, nearest
        first, at most two."""
        best = min(self.own, self.others[0][0])
        near = [c for d, c in self.others if d < self.own and d <= margin * best]
        return tuple(near[:2])


def distances(mine: FloatArray, library: Sequence[FloatArray]) -> FloatArray:
    """(N,) DTW distance from a take's retrieval features to each of ``library``'s, the nearer
    of the take and its mirror image (the exercise done with the other side)."""
    n = min(6, mine.shape[1])
    retriever = MotionRetriever(n_components=n, frame_rate=RETRIEVAL_FPS, metric="features")
    retriever.fit(list(library), list(range(len(library))))
    return np.minimum(retriever.distances(mine), retriever.distances(mirrored_features(mine)))


def comparable(takes: Sequence[FloatArray], columns: int) -> list[FloatArray]:
    """The takes whose features have ``columns`` body-part distances (same feature set)."""
    arrays = [np.asarray(t, dtype=np.float64) for t in takes]
    return [t for t in arrays if t.ndim == 2 and t.shape[1] == columns and len(t)]


def rank(
    motion: Motion,
    model: FittedModel,
    candidates: Sequence[Candidate],
    kin: Kinematics,
    own_takes: Sequence[FloatArray] = (),
) -> Ranking | None:
    """The recording's `Ranking` (None without candidates or when a take's body parts cannot
    be found); ``kin``: the motion's kinematics; ``own_takes``: the exercise's confirmed takes.
    An exercise's distance is the distance to the nearest of its reference and its takes."""
    tutor = model.tutor_parts.features
    if not candidates or tutor.size == 0:
        return None
    try:
        mine = features_of(motion, kin)
    except (AnalysisInputError, ValueError):
        return None
    width = mine.shape[1]
    known = [c for c in candidates if comparable([c.features], width)]
    if not known:
        return None
    groups = [comparable([tutor, *own_takes], width)]
    groups += [comparable(c.references(), width) for c in known]
    found = distances(mine, [take for group in groups for take in group])
    ends = np.cumsum([len(group) for group in groups])
    nearest = [float(found[end - len(g) : end].min()) for end, g in zip(ends, groups, strict=True)]
    others = sorted(zip(nearest[1:], known, strict=True), key=lambda pair: pair[0])
    return Ranking(nearest[0], tuple(others))


def decide(evidence: Evidence, context: MatchContext, options: MatchOptions) -> ExerciseMatch:
    """The verdict and its plain words (see the module docstring)."""
    name = context.exercise_name
    nearer = evidence.nearer is not None and evidence.nearer > options.margin_for(context)
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
    also = ""
    if looks_like is not None:
        second = f" or {evidence.also.name}" if evidence.also is not None else ""
        also = f" It looks more like {looks_like.name}{second}."
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
    context, options = context or MatchContext(), options or MatchOptions()
    evidence = movement_evidence(points, progress, repetitions, model)
    motion, kin = seen
    ranking = rank(motion, model, context.candidates, kin, context.own_takes)
    if ranking is not None:
        named = ranking.named(options.margin_for(context))
        evidence = replace(
            evidence,
            nearer=ranking.nearer(),
            nearest=ranking.others[0][1],
            also=named[1] if len(named) > 1 else None,
        )
    return decide(evidence, context, options)
