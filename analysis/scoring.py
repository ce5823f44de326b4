"""Scores 0–100 for repetitions: distance to the tutor's repetitions, mapped by a calibrated curve.

The distance of a patient repetition is the smallest path-normalised DTW cost to any tutor
repetition, both taken relative to their own starting pose (so body build and where the patient
stands do not count, only the movement). The curve is a logistic function of the distance:
score = 100 / (1 + exp((d − d₅₀) / w)). Cold start (tutor only): d₅₀ and w come from how much
the tutor's own repetitions differ from each other. With labelled recordings, d₅₀ and w are
fitted by logistic regression of "correct" on distance, so a score is the estimated chance (in %)
that a therapist would call the repetition correct.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.dtw import DTWOptions, align

FloatArray = npt.NDArray[np.float64]
_OPTIONS = DTWOptions()


@dataclass(frozen=True)
class ScoreScale:
    """The logistic curve from distance to score: midpoint ``d50`` and width ``w``."""

    d50: float
    width: float
    source: str

    def score(self, distance: float) -> float:
        z = np.clip((distance - self.d50) / max(self.width, 1e-9), -50.0, 50.0)
        return float(100.0 / (1.0 + np.exp(z)))

    def as_dict(self) -> dict[str, float | str]:
        return {"d50": self.d50, "width": self.width, "source": self.source}


def repetition_distance(segment: FloatArray, templates: Sequence[FloatArray]) -> float:
    """Smallest mean-per-step DTW cost of ``segment`` (n, D) to any template (m_k, D)."""
    best = np.inf
    for template in templates:
        result = align(segment, template, _OPTIONS)
        best = min(best, result.cost / len(result.path))
    return float(best)


def _tutor_spread(templates: Sequence[FloatArray]) -> float:
    """Median leave-one-out distance among the tutor's own repetitions."""
    if len(templates) < 2:
        return float(np.mean(np.linalg.norm(templates[0], axis=1))) * 0.1 + 1e-6
    others = [
        repetition_distance(t, [u for j, u in enumerate(templates) if j != k])
        for k, t in enumerate(templates)
    ]
    return float(np.median(others)) + 1e-6


def calibrate_scale(
    templates: Sequence[FloatArray], labelled: Sequence[tuple[float, bool]] = ()
) -> ScoreScale:
    """The score curve (see the module docstring)."""
    classes = {correct for _, correct in labelled}
    if len(classes) == 2:
        from sklearn.linear_model import LogisticRegression

        d = np.array([[x] for x, _ in labelled])
        y = np.array([c for _, c in labelled])
        fit = LogisticRegression(C=10.0).fit(d, y)
        slope, intercept = float(fit.coef_[0, 0]), float(fit.intercept_[0])
        if slope < 0:
            return ScoreScale(-intercept / slope, -1.0 / slope, "labelled recordings")
    spread = _tutor_spread(templates)
    return ScoreScale(3.0 * spread, 0.75 * spread, "tutor repetitions")
