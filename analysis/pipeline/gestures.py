"""Each repetition against its synchronised tutor repetition (papers 000, 001, 003).

Alignment: WOOE-DTW as paper 000 defines it offline for one gesture: quaternion frame cost on the
joints' local rotations, path-length weighting (eq 3) and the exercise's CMA-ES joint weights.

Along that warping path (tutor frames i, patient frames j), paper 001's Table 1:

- *too fast*: many-to-one runs where several tutor frames meet one patient frame; *too slow*: one
  tutor frame held over several patient frames. Reported when the repetition as a whole is that
  much quicker or slower than the tutor's (its duration ratio past ``fast_below`` /
  ``slow_above``), with the patient frames those runs cover.
- *incomplete* / *overdone*: the end of the movement the patient reached, on the exercise's
  progress axis (1 = the tutor's end of range), below ``incomplete_below`` or above
  ``overdone_above``. Incomplete frames: where the path holds one patient frame while the tutor
  goes through its end of range (a non-monotonic many-to-one run); overdone frames: where the
  patient is farther along than the tutor ever goes.

GB-DTW's score (001 eq 8): 100 exp(−mean path cost / scale), the scale set so that the tutor's
own repetitions score about 90. Paper 003's figures, reported separately: alignment quality as the
mean Kendall τ of the displacement vectors (eq 5.13) along the path, and similarity as the mean
angular distance of the involved joints' rotations, in degrees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.dtw import DTWOptions, align, paired_costs, path_groups
from analysis.dtw.metrics import kendall_tau_score
from analysis.kinematics import quaternions as quat
from analysis.pipeline.results import Guidance

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
TUTOR_SCORE = 90.0  # what the tutor's own repetitions score on the GB-DTW scale
TAU_PAIRS = 96


@dataclass(frozen=True)
class GuidanceRules:
    """When a repetition gets each kind of guidance (ratios to the tutor's repetition)."""

    fast_below: float = 0.7
    slow_above: float = 1.5
    incomplete_below: float = 0.7
    overdone_above: float = 1.3
    min_run: int = 2


@dataclass(frozen=True, eq=False)
class GestureAlignment:
    """One repetition's WOOE-DTW alignment with its tutor repetition and what it gives."""

    path: IntArray  # (K, 2) (tutor frame, patient frame), relative to each repetition's start
    mean_cost: float
    alignment_tau: float
    similarity_deg: float


def wooe_options(weights: FloatArray | None) -> DTWOptions:
    """Paper 000's weighted, path-length-weighted DTW on quaternions."""
    w = None if weights is None else tuple(float(v) for v in weights)
    return DTWOptions(cost="quaternion", weights=w, path_length_weighting=True)


def align_gesture(
    tutor_q: FloatArray, patient_q: FloatArray, weights: FloatArray | None
) -> GestureAlignment:
    """Align (m, J, 4) tutor and (n, J, 4) patient rotations of the scored joints."""
    options = wooe_options(weights)
    tutor_q = quat.make_continuous(tutor_q, axis=0)
    patient_q = quat.make_continuous(patient_q, axis=0)
    # each joint in the hemisphere of the tutor's first frame, so q and -q are the same pose
    flip = np.sum(patient_q[0] * tutor_q[0], axis=-1) < 0
    patient_q = patient_q * np.where(flip, -1.0, 1.0)[None, :, None]
    tutor_rows = tutor_q.reshape(len(tutor_q), -1)
    patient_rows = patient_q.reshape(len(patient_q), -1)
    path = np.asarray(align(tutor_rows, patient_rows, options).path)
    costs = paired_costs(
        tutor_rows[path[:, 0]], patient_rows[path[:, 1]], options.cost, options.weights
    )
    angles = quat.angle_between(tutor_q[path[:, 0]], patient_q[path[:, 1]], degrees=True)
    return GestureAlignment(
        path=path,
        mean_cost=float(costs.mean()),
        alignment_tau=round(kendall_tau_score(tutor_q, patient_q, _thinned(path)), 4),
        similarity_deg=round(float(np.mean(angles)), 2),
    )


def _thinned(path: IntArray) -> IntArray:
    """At most `TAU_PAIRS` evenly spaced cells of a path: Kendall's τ costs the square of the
    pairs it compares, and a repetition's shape is plain at that resolution."""
    stride = -(-len(path) // TAU_PAIRS)
    return path[::stride]


def gesture_score(mean_cost: float, scale: float) -> float:
    """001 eq 8 on the 0–100 scale."""
    return round(100.0 * math.exp(-mean_cost / max(scale, 1e-12)), 2)


def score_scale(tutor_costs: list[float]) -> float:
    """The scale at which the tutor's own repetitions (their mean cost to each other) score
    `TUTOR_SCORE`."""
    typical = float(np.median(tutor_costs)) if tutor_costs else 0.0
    return max(typical, 1e-6) / math.log(100.0 / TUTOR_SCORE)


def _runs(path: IntArray, min_run: int) -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
    """Patient-frame spans of the many-to-one runs: several tutor frames on one patient frame
    (fast), one tutor frame on several patient frames (slow)."""
    fast, slow = [], []
    for s, e in path_groups(path):
        if e - s < min_run:
            continue
        i, j = path[s:e, 0], path[s:e, 1]
        if i[0] != i[-1]:
            fast.append((int(j[0]), int(j[-1])))
        else:
            slow.append((int(j[0]), int(j[-1])))
    return fast, slow


def _span(runs: list[tuple[int, int]], n: int) -> tuple[int, int]:
    if not runs:
        return 0, n - 1
    return min(a for a, _ in runs), max(b for _, b in runs)


def guidance(
    alignment: GestureAlignment,
    patient_progress: FloatArray,
    tutor_reach: float,
    rules: GuidanceRules,
) -> tuple[Guidance, ...]:
    """Table 1 guidance for one repetition, most pressing first; frames relative to its start.

    patient_progress: (n,) the repetition's progress signal relative to its first frame (tutor
    units); tutor_reach: how far along the axis the matched tutor repetition goes."""
    path, n = alignment.path, len(patient_progress)
    m = int(path[:, 0].max()) + 1
    fast, slow = _runs(path, rules.min_run)
    tempo = n / max(m, 1)
    reach = float(patient_progress.max()) / max(tutor_reach, 1e-9)
    found: list[tuple[float, Guidance]] = []
    if tempo < rules.fast_below:
        found.append((rules.fast_below / tempo, Guidance("too fast", _span(fast, n))))
    if tempo > rules.slow_above:
        found.append((tempo / rules.slow_above, Guidance("too slow", _span(slow, n))))
    if reach < rules.incomplete_below:
        held = Guidance("incomplete", _held(path, n))
        found.append((rules.incomplete_below / max(reach, 1e-3), held))
    if reach > rules.overdone_above:
        beyond = np.flatnonzero(patient_progress > tutor_reach)
        frames = (int(beyond[0]), int(beyond[-1])) if beyond.size else (0, n - 1)
        found.append((reach / rules.overdone_above, Guidance("overdone", frames)))
    return tuple(g for _, g in sorted(found, key=lambda item: -item[0]))


def _held(path: IntArray, n: int) -> tuple[int, int]:
    """Patient frames where the path stays while the tutor goes on (the longest run of several
    tutor frames on one patient frame): where the movement stopped short."""
    best = (0, n - 1)
    longest = 0
    for s, e in path_groups(path):
        i = path[s:e, 0]
        if i[0] != i[-1] and e - s > longest:
            longest, best = e - s, (int(path[s, 1]), int(path[e - 1, 1]))
    return best
