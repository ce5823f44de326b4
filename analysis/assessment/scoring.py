"""Scores 0–100 for repetitions from per-joint deviations from the tutor's repetitions.

A repetition is compared with every tutor repetition, both taken relative to their own starting
pose (so body build and where the patient stands do not count, only the movement). DTW aligns it
with the closest tutor repetition; along that path the mean distance of each joint gives a
deviation vector (J,), in body sizes. `repetition_features` adds, per joint, how much farther
(or less far) from its starting position the joint travels than in that tutor repetition (J,):
a reduced range of motion and a compensation both show there even when DTW, which may stretch
time freely, finds a close path. Deviations are standardised by how much the tutor's own
repetitions deviate from each other (leave one out), so a joint that normally stays still and
moves here (a compensation) stands out as much as a main joint that falls short.

Cold start (tutor only): the *excess* z = mean over joints of max(0, zⱼ) is mapped to a score by
100 / (1 + exp((z − z₅₀) / w)) with z₅₀ = `COLD_MIDPOINT` and w = `COLD_WIDTH` standard deviations.
With labelled recordings: a logistic regression of "correct" on the repetition features (both
parts, each feature scaled to unit variance over the labelled repetitions), so a score is the
estimated chance (in %) that a therapist would call the repetition correct, averaged with the
cold-start score (`TUTOR_WEIGHT`). A few labelled people teach a classifier their own styles as
much as their errors (on UI-PRMD, leave-one-subject-out, a subject whose correct takes move
unlike the other five is scored as incorrect); the tutor-based score does not depend on who was
labelled and keeps such a subject's correct takes above their incorrect ones.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.dtw import DTWOptions, align

FloatArray = npt.NDArray[np.float64]
_OPTIONS = DTWOptions()
COLD_MIDPOINT = 1.5
COLD_WIDTH = 0.5
SIGMA_FLOOR = 0.01  # body sizes: no joint is trusted to repeat closer than 1 % of body size
TUTOR_WEIGHT = 0.5  # share of the tutor-based score in a trained score (see the module docstring)
TRAINED_C = 0.05  # inverse L2 strength: ~500 labelled repetitions, 2J ≈ 40 correlated features


def joint_deviations(segment: FloatArray, template: FloatArray) -> tuple[FloatArray, float]:
    """Per-joint mean distance (J,) along the DTW path of (n, 3J) vs (m, 3J), and its cost."""
    result = align(segment, template, _OPTIONS)
    i, j = result.path[:, 0], result.path[:, 1]
    diff = (segment[i] - template[j]).reshape(len(i), -1, 3)
    return np.linalg.norm(diff, axis=-1).mean(axis=0), result.cost / len(i)


def _closest(segment: FloatArray, templates: Sequence[FloatArray]) -> tuple[FloatArray, int]:
    """Deviation vector (J,) to the closest template (smallest mean path cost) and its index."""
    best: tuple[float, FloatArray, int] | None = None
    for k, template in enumerate(templates):
        dev, cost = joint_deviations(segment, template)
        if best is None or cost < best[0]:
            best = (cost, dev, k)
    assert best is not None
    return best[1], best[2]


def deviations(segment: FloatArray, templates: Sequence[FloatArray]) -> FloatArray:
    """Deviation vector (J,) to the closest tutor repetition (smallest mean path cost)."""
    return _closest(segment, templates)[0]


def joint_reach(movement: FloatArray) -> FloatArray:
    """Per joint (J,), the farthest it gets from its starting position in (n, 3J) rows that are
    relative to the repetition's start."""
    return np.linalg.norm(movement.reshape(len(movement), -1, 3), axis=-1).max(axis=0)


def repetition_features(segment: FloatArray, templates: Sequence[FloatArray]) -> FloatArray:
    """(2J,): the deviation vector to the closest tutor repetition, then each joint's reach minus
    its reach in that repetition (see the module docstring); both in body sizes."""
    dev, k = _closest(segment, templates)
    return np.concatenate([dev, joint_reach(segment) - joint_reach(templates[k])])


def repetition_distance(segment: FloatArray, templates: Sequence[FloatArray]) -> float:
    """Smallest mean-per-step DTW cost of ``segment`` (n, D) to any template (m_k, D)."""
    return float(min(joint_deviations(segment, t)[1] for t in templates))


@dataclass(frozen=True, eq=False)
class RepetitionScorer:
    """Turns a deviation vector into a score (see the module docstring)."""

    mean: FloatArray
    spread: FloatArray
    classifier: Any = None

    @property
    def source(self) -> str:
        return "labelled recordings" if self.classifier is not None else "tutor repetitions"

    def standardise(self, dev: FloatArray) -> FloatArray:
        return (dev - self.mean) / self.spread

    def score(self, features: FloatArray) -> float:
        """Score 0–100 of `repetition_features` (2J,) or of a bare deviation vector (J,) (cold
        start only: a trained classifier needs both parts)."""
        z = self.standardise(features[: self.mean.size])
        excess = float(np.mean(np.maximum(z, 0.0)))
        cold = 100.0 / (1.0 + np.exp(np.clip((excess - COLD_MIDPOINT) / COLD_WIDTH, -50, 50)))
        if self.classifier is None:
            return float(cold)
        learnt = 100.0 * self.classifier.predict_proba(features[None])[0, 1]
        return float((1.0 - TUTOR_WEIGHT) * learnt + TUTOR_WEIGHT * cold)

    def as_dict(self) -> dict[str, Any]:
        return {"source": self.source, "joints": int(self.mean.size)}


def tutor_statistics(templates: Sequence[FloatArray]) -> tuple[FloatArray, FloatArray]:
    """Mean and spread (J,) of the tutor's leave-one-out deviations."""
    if len(templates) < 2:
        n_joints = templates[0].shape[1] // 3
        return np.zeros(n_joints), np.full(n_joints, 5 * SIGMA_FLOOR)
    loo = np.array([
        deviations(t, [u for k, u in enumerate(templates) if k != i])
        for i, t in enumerate(templates)
    ])  # fmt: skip
    spread = np.maximum(loo.std(axis=0), np.maximum(0.25 * loo.mean(axis=0), SIGMA_FLOOR))
    return loo.mean(axis=0), spread


def fit_scorer(
    templates: Sequence[FloatArray], labelled: Sequence[tuple[FloatArray, bool]] = ()
) -> RepetitionScorer:
    """Cold-start scorer from the tutor; with both classes labelled (`repetition_features`, is
    correct), a fitted classifier too."""
    mean, spread = tutor_statistics(templates)
    scorer = RepetitionScorer(mean, spread)
    if len({correct for _, correct in labelled}) < 2:
        return scorer
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    x = np.array([features for features, _ in labelled])
    y = np.array([correct for _, correct in labelled])
    classifier = make_pipeline(
        StandardScaler(), LogisticRegression(C=TRAINED_C, class_weight="balanced", max_iter=3000)
    ).fit(x, y)
    return RepetitionScorer(mean, spread, classifier)
