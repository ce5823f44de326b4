"""The parts of an exercise model that the papers' stages need, fitted from the tutor (and any
labelled recordings): the key-pose model (004 ch. 5–6), the WOOE-DTW joint weights (000 §4.2,
CMA-ES), the GB-DTW score scale and the pass threshold (001 eqs 13–15).

A cold start (tutor only) trains on augmented copies of the tutor, as the design says: the
key-pose classifier on warped, range-reduced copies (`analysis.landmarks.signature`), the joint
weights on time-warped copies whose key poses are known. The pass threshold is the same stated
number on every exercise (`PASS_SCORE`, 70): what is fitted is where the raw score's own pass
boundary lies (001 eqs 13–15 on labelled repetitions; the cold scorer's calibrated boundary
otherwise), and the scorer maps that boundary onto 70 (`analysis.assessment.scoring`).
"""

from __future__ import annotations

import itertools
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.assessment.scoring import PASS_SCORE
from analysis.bvh import Motion
from analysis.dtw.joint_weights import JointWeightOptimizer
from analysis.dtw.metrics import segment_labels
from analysis.kinematics import normalised_positions, rotations
from analysis.kinematics import quaternions as quat
from analysis.landmarks.evaluation import evaluate, summed
from analysis.landmarks.identification import LandmarkModel, LandmarkOptions
from analysis.online import BayesThreshold
from analysis.pipeline.gestures import align_gesture, score_scale, wooe_options

FloatArray = npt.NDArray[np.float64]
WEIGHT_GENERATIONS = 8
WEIGHT_FPS = 10.0  # joint weights decide which joints matter: a coarse timeline is enough
WARPED_COPIES = 3
CV_FOLDS = 3


@dataclass(frozen=True)
class PassThreshold:
    """The score (0–100) a repetition needs to pass (always `PASS_SCORE`), how the scale was
    calibrated, and the raw score (classifier blend) that the calibration maps onto it."""

    value: float
    source: str  # starts "labelled repetitions" or "tutor variation" (the web app reads which)
    raw: float = PASS_SCORE


def fit_landmarks(
    tutor: Motion,
    frames: Sequence[int],
    types: Sequence[int],
    training: Sequence[tuple[Motion, Sequence[int], Sequence[int]]],
    options: LandmarkOptions | None = None,
) -> LandmarkModel:
    """The key-pose model; labelled recordings must be at the tutor's frame rate."""
    model = LandmarkModel(options=options or LandmarkOptions())
    return model.fit(tutor, list(frames), list(types), training=list(training))


def landmark_precision(
    tutor: Motion,
    frames: Sequence[int],
    types: Sequence[int],
    training: Sequence[tuple[Motion, Sequence[int], Sequence[int]]],
    options: LandmarkOptions | None = None,
) -> float | None:
    """Cross-validated precision π (004 eq 5.36) of the final key poses on the labelled
    recordings: `CV_FOLDS` folds, each held-out recording detected by a model fitted on the tutor
    and the other folds; None with fewer than two labelled recordings."""
    if len(training) < 2:
        return None
    folds = min(CV_FOLDS, len(training))
    scores = []
    for k in range(folds):
        rest = [t for i, t in enumerate(training) if i % folds != k]
        model = fit_landmarks(tutor, frames, types, rest, options)
        for motion, f, t in training[k::folds]:
            found = model.detect(motion).landmarks
            data = normalised_positions(motion).reshape(motion.n_frames, -1)
            scores.append(evaluate(found.frames, found.types, f, t, data))
    return round(summed(scores).precision, 3)


def _warped(q: FloatArray, frames: Sequence[int], rng: np.random.Generator) -> tuple:
    """A smoothly time-warped copy of rotations (F, J, 4) and where its key poses went."""
    n = len(q)
    tempo = np.exp(np.convolve(rng.normal(0.0, 0.3, n), np.ones(15) / 15, mode="same"))
    times = np.concatenate([[0.0], np.cumsum(tempo)])[:n]
    times *= (n - 1) / times[-1]
    n_out = max(4, round(n * rng.uniform(0.75, 1.3)))
    at = np.interp(np.linspace(0, n - 1, n_out), np.arange(n), times)
    low = np.clip(np.floor(at).astype(int), 0, n - 2)
    copy = quat.slerp(q[low], q[low + 1], (at - low)[:, None])
    moved = np.searchsorted(at, np.asarray(frames, dtype=np.float64))
    return copy, np.minimum(moved, n_out - 1)


def fit_joint_weights(
    tutor_q: FloatArray,
    frames: Sequence[int],
    labelled: Sequence[tuple[FloatArray, Sequence[int]]],
    seed: int = 0,
) -> tuple[FloatArray, float, float]:
    """CMA-ES joint weights (J,) for WOOE-DTW between the tutor's rotations (F, J, 4) and the
    labelled (or warped) recordings' rotations with their key-pose frames; also the alignment
    error (eq 5) before and after. Segments are the stretches between consecutive key poses."""
    rng = np.random.default_rng(seed)
    takes = list(labelled) or [_warped(tutor_q, frames, rng) for _ in range(WARPED_COPIES)]
    ref_labels = segment_labels(len(tutor_q), np.asarray(frames))
    optimiser = JointWeightOptimizer(
        options=wooe_options(None), iterations=WEIGHT_GENERATIONS, target="path", seed=seed,
        n_threads=1,
    )  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        optimiser.fit(
            tutor_q.reshape(len(tutor_q), -1),
            ref_labels,
            [q.reshape(len(q), -1) for q, _ in takes],
            [segment_labels(len(q), np.asarray(f)) for q, f in takes],
        )
    return optimiser.weights_, optimiser.initial_error_, optimiser.error_


def tutor_gesture_scale(
    tutor_q: FloatArray, reps: Sequence[tuple[int, int]], weights: FloatArray
) -> float:
    """GB-DTW score scale from the tutor's repetitions aligned with each other."""
    costs = [
        align_gesture(tutor_q[a : b + 1], tutor_q[c : d + 1], weights).mean_cost
        for (a, b), (c, d) in itertools.combinations(reps[:6], 2)
    ]
    if not costs:  # one repetition: its cost against itself a tenth of a repetition later
        a, b = reps[0]
        shift = max(1, (b - a) // 10)
        moved = tutor_q[min(a + shift, b) : b + 1]
        costs = [align_gesture(tutor_q[a : b + 1], moved, weights).mean_cost]
    return score_scale(costs)


def pass_threshold(scores: Sequence[float], correct: Sequence[bool]) -> PassThreshold:
    """Where the raw scores of labelled repetitions pass: 001 eqs 13–15 when both classes have two
    or more; else the cold scorer's own boundary, already at `PASS_SCORE` (module docstring)."""
    y = np.asarray(correct, dtype=bool)
    if min(int(y.sum()), int((~y).sum())) >= 2:
        try:
            bayes = BayesThreshold().fit(np.asarray(scores, float), ~y)
        except (ValueError, np.linalg.LinAlgError):
            bayes = None
        if bayes is not None and np.isfinite(bayes.threshold_):
            value = float(np.clip(bayes.threshold_, 1.0, 99.0))
            source = "labelled repetitions (Bayes, 001 eqs 13-15), mapped onto the one scale"
            return PassThreshold(PASS_SCORE, source, round(value, 2))
    return PassThreshold(PASS_SCORE, "tutor variation, on the one scale")


def rotations_at(motion: Motion, index: Sequence[int]) -> FloatArray:
    """Local rotations (F, J, 4) of the given joints."""
    return rotations(motion)[:, list(index)]


@dataclass(frozen=True, eq=False)
class PaperParts:
    """Everything the key-pose, alignment and pass/fail stages read (see the module docstring).

    ``joint_index``: the involved joints (model order) that WOOE-DTW aligns, with their
    ``joint_weights``; ``weight_error``: eq 5's alignment error before and after CMA-ES;
    ``tutor_q`` (F, J, 4) their rotations and ``tutor_progress`` (F,) the tutor on the progress
    axis, at the model's frame rate; ``gesture_scale``: GB-DTW's score scale."""

    landmarks: LandmarkModel
    joint_index: tuple[int, ...]
    joint_weights: FloatArray
    weight_error: tuple[float, float]
    tutor_q: FloatArray
    tutor_progress: FloatArray
    gesture_scale: float
    threshold: PassThreshold
    precision: float | None = None  # cross-validated key-pose precision (labelled recordings)

    def report(self) -> dict[str, object]:
        """The training report's entries for these parts (JSON-ready)."""
        options = self.landmarks.options
        return {
            "key_poses": {
                "classifier": options.classifier + (" + AdaBoost" if options.adaboost else ""),
                "refining": f"{options.refine.clustering} clustering, "
                f"{options.refine.selection} selection",
                "periodic_patterns": [list(p) for p in self.landmarks.patterns_],
                "cross_validated_precision": self.precision,
            },
            "joint_weights": [round(float(w), 4) for w in self.joint_weights],
            "alignment_error": {
                "before": round(self.weight_error[0], 4),
                "after": round(self.weight_error[1], 4),
            },
            "pass_threshold": {
                "value": self.threshold.value,
                "source": self.threshold.source,
                "raw_score_at_pass": self.threshold.raw,
            },
            "gesture_scale": round(self.gesture_scale, 6),
        }


def fit_paper_parts(  # noqa: PLR0917 (the tutor's parts as fit_components holds them)
    tutor: Motion,
    frames: Sequence[int],
    types: Sequence[int],
    joint_index: Sequence[int],
    progress: FloatArray,
    reps: Sequence[tuple[int, int]],
    training: Sequence[tuple[Motion, list[int], list[int]]],
    scored: Sequence[tuple[float, bool]],
) -> PaperParts:
    """Fit every part; ``training``: labelled recordings at the tutor's frame rate; ``scored``:
    (raw score, is correct) of the labelled repetitions; ``progress``: the tutor's progress
    signal."""
    landmarks = fit_landmarks(tutor, frames, types, training)
    index = list(joint_index)
    tutor_q = rotations_at(tutor, index)
    step = max(1, round(tutor.fps / WEIGHT_FPS))
    labelled = [(rotations_at(m, index)[::step], [f // step for f in f_]) for m, f_, _ in training]
    weights, before, after = fit_joint_weights(
        tutor_q[::step], [f // step for f in frames], labelled
    )
    scale = tutor_gesture_scale(tutor_q, list(reps), weights)
    return PaperParts(
        landmarks=landmarks,
        joint_index=tuple(index),
        joint_weights=weights,
        weight_error=(float(before), float(after)),
        tutor_q=tutor_q,
        tutor_progress=np.asarray(progress, dtype=np.float64),
        gesture_scale=scale,
        threshold=pass_threshold([s for s, _ in scored], [c for _, c in scored]),
        precision=landmark_precision(tutor, frames, types, training),
    )
