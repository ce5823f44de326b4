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

One calibrated scale: a repetition passes at `PASS_SCORE` (70) on every exercise, so "passed"
means the same everywhere. The score is calibrated, not the threshold: each model maps its raw
figure so that its own pass boundary lands on 70.

Cold start (tutor only): the *badness* b is the larger of two ratios, each 1 at the pass boundary:
the *excess* (mean over joints of how much farther the joint is from the closest tutor repetition
than the tutor's own repetitions are from each other, max(0, devⱼ − meanⱼ)) in units of the
tutor's repetition-to-repetition distance (``scale``: the mean over joints of meanⱼ), over
`COLD_PASS_EXCESS`; and the largest *reach shortfall* of a joint the tutor moves (1 − its reach /
the tutor's, over the joints reaching at least half as far as the tutor's farthest) over
`SHORTFALL_PASS`. Measuring the excess in the tutor's own repetition-to-repetition distance
calibrates the boundary per exercise: a squat's whole body wanders more between people than a
shoulder raise's, and so does the tutor's between repetitions. The second ratio catches a body part
the tutor moves and the patient leaves still (one arm raised of two): averaged over 20 joints its
deviation is small, but its reach is nearly zero. The score is 100 / (1 + ³⁄₇·exp((b − 1)/w)),
70 at b = 1, about 97 for a repetition like the tutor's. `COLD_PASS_EXCESS` (one global margin,
1.5 tutor distances) and `SHORTFALL_PASS` (0.5) are the cut that best separates correct from
incorrect UI-PRMD dev sessions on all ten exercises at once; agreement stays ≥ 90 % for margins
1.3–1.8, and 89 % when the margin is learnt without the exercise it is tested on
(docs/sections/assessment_design.md).

With labelled recordings: a logistic regression of "correct" on the repetition features (both
parts, each feature scaled to unit variance over the labelled repetitions), so a raw score is the
estimated chance (in %) that a therapist would call the repetition correct, averaged with the
cold-start score (`TUTOR_WEIGHT`). A few labelled people teach a classifier their own styles as
much as their errors (on UI-PRMD, leave-one-subject-out, a subject whose correct takes move
unlike the other five is scored as incorrect); the tutor-based score does not depend on who was
labelled and keeps such a subject's correct takes above their incorrect ones. The raw score's
own pass boundary (paper 001's Bayes boundary between the labelled classes, fitted in
`analysis.pipeline.model_parts`) is then mapped onto 70 by `calibrated` (piecewise linear, 0 and
100 kept).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.dtw import DTWOptions, align
from analysis.dtw.nearest import closest_paths

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
_OPTIONS = DTWOptions()
PASS_SCORE = 70.0  # the one pass threshold of every exercise (0–100 scale)
COLD_PASS_EXCESS = 1.5  # mean excess, in tutor repetition distances, at the pass boundary
SHORTFALL_PASS = 0.5  # a moving joint reaching half of the tutor's reach is at the boundary
SCALE_FLOOR = 0.001  # body sizes: the tightest UI-PRMD tutor repeats at 0.0016
# one tutor repetition has no repetition distance: the boundary then sits at a mean excess of
# 2.5 % of body size (what the tutor-spread floor gave before the scale existed)
ONE_REPETITION_SCALE = 0.025 / COLD_PASS_EXCESS
MOVING_SHARE = 0.5  # joints reaching at least half the tutor's farthest joint are "moving"
COLD_WIDTH = 0.7  # badness units per e-fold of the odds (wide: scores keep their order)
_PASS_ODDS = (100.0 - PASS_SCORE) / PASS_SCORE
MISSED_SHARE = 0.5  # share of joints at the worst level that makes a key pose "clearly missed"
MISSED_CAP = PASS_SCORE - 5.0  # the highest score of a repetition that clearly missed a key pose
SIGMA_FLOOR = 0.01  # body sizes: no joint is trusted to repeat closer than 1 % of body size
TUTOR_WEIGHT = 0.5  # share of the tutor-based score in a trained score (see the module docstring)
TRAINED_C = 0.05  # inverse L2 strength: ~500 labelled repetitions, 2J ≈ 40 correlated features


def joint_deviations(segment: FloatArray, template: FloatArray) -> tuple[FloatArray, float]:
    """Per-joint mean distance (J,) along the DTW path of (n, 3J) vs (m, 3J), and its cost."""
    result = align(segment, template, _OPTIONS)
    return _along_path(segment, template, result.path), result.cost / len(result.path)


def _along_path(segment: FloatArray, template: FloatArray, path: IntArray) -> FloatArray:
    """Per-joint mean distance (J,) between the frames the DTW path pairs."""
    i, j = path[:, 0], path[:, 1]
    diff = (segment[i] - template[j]).reshape(len(i), -1, 3)
    return np.asarray(np.linalg.norm(diff, axis=-1).mean(axis=0), dtype=np.float64)


def _closest(segment: FloatArray, templates: Sequence[FloatArray]) -> tuple[FloatArray, int]:
    """Deviation vector (J,) to the closest template (smallest mean path cost) and its index;
    the deviations are measured along the closest template's path only."""
    return _closest_all([segment], templates)[0]


def _closest_all(
    segments: Sequence[FloatArray], templates: Sequence[FloatArray]
) -> list[tuple[FloatArray, int]]:
    """`_closest` of every segment, their alignments in one compiled call."""
    found = closest_paths(segments, templates)
    return [
        (_along_path(s, templates[k], path), k)
        for s, (k, path) in zip(segments, found, strict=True)
    ]


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
    return repetition_features_all([segment], templates)[0]


def repetition_features_all(
    segments: Sequence[FloatArray], templates: Sequence[FloatArray]
) -> list[FloatArray]:
    """`repetition_features` of every segment (a recording's repetitions), aligned at once."""
    return [
        np.concatenate([dev, joint_reach(segment) - joint_reach(templates[k])])
        for segment, (dev, k) in zip(segments, _closest_all(segments, templates), strict=True)
    ]


def repetition_distance(segment: FloatArray, templates: Sequence[FloatArray]) -> float:
    """Smallest mean-per-step DTW cost of ``segment`` (n, D) to any template (m_k, D)."""
    return float(min(joint_deviations(segment, t)[1] for t in templates))


def cold_score(badness: float) -> float:
    """The cold-start score of a badness (1 at the pass boundary → `PASS_SCORE`)."""
    odds = _PASS_ODDS * np.exp(np.clip((badness - 1.0) / COLD_WIDTH, -50.0, 50.0))
    return float(100.0 / (1.0 + odds))


def calibrated(raw: float, raw_pass: float) -> float:
    """Map a raw score 0–100 whose pass boundary is ``raw_pass`` onto the one scale: piecewise
    linear through (0, 0), (raw_pass, `PASS_SCORE`), (100, 100), so the order is kept."""
    raw_pass = float(np.clip(raw_pass, 1.0, 99.0))
    if raw <= raw_pass:
        return float(PASS_SCORE * raw / raw_pass)
    return float(PASS_SCORE + (100.0 - PASS_SCORE) * (raw - raw_pass) / (100.0 - raw_pass))


@dataclass(frozen=True, eq=False)
class RepetitionScorer:
    """Turns repetition features into a score on the one scale (see the module docstring).

    ``tutor_reach`` (J,): each joint's mean reach in the tutor's repetitions; ``raw_pass``: the
    raw score (classifier blend) at the labelled pass boundary, mapped onto `PASS_SCORE`;
    ``scale``: the tutor's repetition-to-repetition distance (body sizes), the excess's unit."""

    mean: FloatArray
    spread: FloatArray
    classifier: Any = None
    tutor_reach: FloatArray | None = None
    raw_pass: float = PASS_SCORE
    scale: float = ONE_REPETITION_SCALE

    @property
    def source(self) -> str:
        return "labelled recordings" if self.classifier is not None else "tutor repetitions"

    def standardise(self, dev: FloatArray) -> FloatArray:
        return (dev - self.mean) / self.spread

    def shortfall(self, features: FloatArray) -> FloatArray:
        """Per joint (J,), 1 − reach / the tutor's reach for the joints the tutor moves (0 for
        the others, and for all when ``features`` holds no reach part)."""
        n = self.mean.size
        out = np.zeros(n)
        if self.tutor_reach is None or features.size < 2 * n:
            return out
        reach = self.tutor_reach + features[n : 2 * n]
        moving = self.tutor_reach >= MOVING_SHARE * float(self.tutor_reach.max())
        moving &= self.tutor_reach > 0.0
        out[moving] = np.maximum(0.0, 1.0 - reach[moving] / self.tutor_reach[moving])
        return out

    def badness(self, features: FloatArray) -> float:
        """1 at the pass boundary of the cold-start score (see the module docstring)."""
        over = np.maximum(features[: self.mean.size] - self.mean, 0.0)
        excess = float(np.mean(over)) / max(self.scale, SCALE_FLOOR)
        short = float(self.shortfall(features).max())
        return max(excess / COLD_PASS_EXCESS, short / SHORTFALL_PASS)

    def raw_score(self, features: FloatArray) -> float:
        """The uncalibrated score: the cold-start score, blended with the classifier's."""
        cold = cold_score(self.badness(features))
        if self.classifier is None:
            return cold
        learnt = 100.0 * self.classifier.predict_proba(features[None])[0, 1]
        return float((1.0 - TUTOR_WEIGHT) * learnt + TUTOR_WEIGHT * cold)

    def score(self, features: FloatArray) -> float:
        """Score 0–100 of `repetition_features` (2J,) or of a bare deviation vector (J,) (cold
        start only: a trained classifier needs both parts); passes at `PASS_SCORE`."""
        return calibrated(self.raw_score(features), self.raw_pass)

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
    reach = np.mean([joint_reach(t) for t in templates], axis=0)
    scale = float(mean.mean()) if len(templates) >= 2 else ONE_REPETITION_SCALE
    scorer = RepetitionScorer(mean, spread, tutor_reach=reach, scale=scale)
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
    return RepetitionScorer(mean, spread, classifier, tutor_reach=reach, scale=scale)


def missed_key_pose(levels: Sequence[Mapping[str, int]], worst: int) -> bool:
    """Whether at some key pose of a repetition (its per-joint levels, end-of-range poses only) at
    least `MISSED_SHARE` of the assessed joints are at the ``worst`` level: the per-joint
    assessment says the pose was clearly missed, so the repetition cannot pass. One joint alone
    does not decide it: Kinect-class rigs put single joints (a hand's roll) at the worst level in
    about 40 % of correct UI-PRMD repetitions, half of the joints in 3 %."""
    return any(
        pose and sum(v >= worst for v in pose.values()) >= MISSED_SHARE * len(pose)
        for pose in levels
    )
