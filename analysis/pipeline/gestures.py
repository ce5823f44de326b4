"""Each repetition against its synchronised tutor repetition (papers 000, 001, 003).

Alignment: WOOE-DTW as paper 000 defines it offline for one gesture: quaternion frame cost on the
joints' local rotations, path-length weighting (eq 3) and the exercise's CMA-ES joint weights.

Along that warping path (tutor frames i, patient frames j), paper 001's Table 1:

- *too fast* / *too slow* (`Pace.tempo`): the repetition's duration over the reference's (the
  median of the tutor's repetitions), judged twice: against the reference (`GuidanceRules`
  ``reference``: far from the tutor's pace whoever the patient is; ``known_reference``, wider,
  once an earlier session is known) and against the patient's own pace (ratios to the patient's
  usual tempo: the median of an earlier session's repetitions when known, ``own``, else of
  this session's repetitions so far, ``so_far``). The
  frames: the many-to-one runs of the warping path (several tutor frames on one patient frame:
  fast; one tutor frame held over several patient frames: slow).
- *incomplete* / *overdone* (`Pace.reach`): the angular excursion of the involved joints (each
  joint's largest rotation away from the repetition's first pose, weighted by how far the tutor
  moves it) over the reference's (per joint, the median over the tutor's repetitions), judged
  against the reference and the patient's own reach in the same way. Incomplete frames: where
  the path holds one patient frame while the tutor goes on; overdone frames: where the patient's
  excursion passes the tutor's largest.

`pace_guidance` is the one rule: the offline pipeline (`analysis.pipeline.repetition_stage`) and
the live aligner (`analysis.live.aligner`) both call `repetition_guidance`.

GB-DTW's score (001 eq 8): 100 exp(−mean path cost / scale), the scale set so that the tutor's
own repetitions score about 90. Paper 003's figures, reported separately: alignment quality as the
mean Kendall τ of the displacement vectors (eq 5.13) along the path, and similarity as the mean
angular distance of the involved joints' rotations, in degrees.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass, replace

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
    """When a repetition gets each kind of guidance: bands (too fast below, too slow above,
    incomplete below, overdone above) on the ratios to the reference's tempo and reach
    (``reference`` in a first session, ``known_reference`` once an earlier session's pace says
    what is usual for this patient) and on the ratios to the patient's usual pace (``own`` for an
    earlier session's, ``so_far`` for this session's repetitions so far).

    Why these figures (docs/EVALUATION.md, "Guidance (paper 001, Table 1)"): on UI-PRMD's
    development subjects, correct takes last 0.88–1.43 times the tutor's repetition and reach
    0.57–1.06 of its excursion (10th–90th percentile of the takes' medians), about as far apart
    as a whole take re-timed ×0.6 / ×1.6 or scaled ×0.6 / ×1.3, so in a first session no band
    names every mistake and leaves every correct take alone: 0.86 / 1.5 and 0.55 / 1.2 trade the
    two. Once an earlier session is known, the patient's own pace names the change and the
    reference's tempo band only keeps a 1.6× change (either way) from ever being hidden. The
    bands against this session's repetitions so far are wider than an earlier session's: they
    catch one repetition rushed or cut short among steady ones, not a take's natural spread."""

    reference: tuple[float, float, float, float] = (0.86, 1.5, 0.55, 1.2)
    known_reference: tuple[float, float, float, float] = (0.65, 1.55, 0.3, 3.0)
    own: tuple[float, float, float, float] = (0.75, 1.3, 0.7, 1.12)
    so_far: tuple[float, float, float, float] = (0.65, 1.5, 0.55, 1.3)
    min_run: int = 2


@dataclass(frozen=True)
class Pace:
    """A repetition, or a patient's usual repetition, against the reference: tempo (duration
    ratio, > 1 slower) and reach (angular excursion ratio of the involved joints, > 1 farther);
    earlier: a usual pace from an earlier session (not this one's repetitions so far)."""

    tempo: float
    reach: float
    earlier: bool = False


def usual_pace(paces: Sequence[Pace]) -> Pace | None:
    """The median tempo and reach of some repetitions (None for none)."""
    if not paces:
        return None
    # statistics' median: numpy's value (the middle one, or the two middle ones' sum halved)
    # without its array set-up, as a session asks after each of its repetitions
    return Pace(
        float(statistics.median([p.tempo for p in paces])),
        float(statistics.median([p.reach for p in paces])),
    )


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


def excursion(q: FloatArray) -> FloatArray:
    """(n, J) each joint's rotation away from the first frame (degrees) of (n, J, 4) rotations."""
    q = quat.make_continuous(q, axis=0)
    return np.asarray(quat.angle_between(q[:1], q, degrees=True), dtype=np.float64)


def reference_excursion(
    tutor_q: FloatArray, tutor_mirror_q: FloatArray, reps: Sequence[tuple[int, int]], step: int
) -> FloatArray:
    """(J,) per involved joint and its mirror image's joint together, the median over the
    tutor's repetitions of their largest excursion: (F, J, 4) rotations of both."""
    spans = list(reps) or [(0, len(tutor_q) - 1)]
    pairs = [
        (excursion(tutor_q[a : b + 1 : step]) + excursion(tutor_mirror_q[a : b + 1 : step]))
        for a, b in spans
    ]
    return np.asarray(np.median([p.max(axis=0) for p in pairs], axis=0), dtype=np.float64)


def reach_series(q: FloatArray, mirror_q: FloatArray, reference: FloatArray) -> FloatArray:
    """(n,) the involved joints' excursion with their mirror images' (so either side, and
    alternating sides, count alike), weighted by the reference's, over the reference's (1 = as
    far as the tutor)."""
    w = reference / max(float(reference.sum()), 1e-9)
    moved = excursion(q) + excursion(mirror_q)
    return np.asarray(moved @ w / max(float(w @ reference), 1e-9), dtype=np.float64)


def pace_guidance(pace: Pace, own: Pace | None, rules: GuidanceRules) -> list[tuple[str, float]]:
    """The one tempo and reach rule (offline and live): the types that apply, each with how far
    past its threshold the repetition is (> 1), most pressing first; ``own``: the patient's usual
    pace (None: judged against the reference alone).

    Tempo (paper 001, issue 34): the repetition's duration over the reference's, against the
    reference's band whether or not an earlier session is known (once one is, the band still
    names a 1.6× change either way: a patient's usual pace never hides it, it only softens the
    words: `usual_for_patient`); and against the patient's usual tempo, in the direction away
    from the reference only (a repetition slower than usual but quicker than the demonstration
    is not told to speed up). Reach against both too (both directions may apply:
    `analysis.pipeline.judgement` keeps one per axis). The bands: `GuidanceRules`."""
    mine = own or Pace(1.0, 1.0)
    fast, slow, short, far = rules.known_reference if mine.earlier else rules.reference
    own_fast, own_slow, own_short, own_far = rules.own if mine.earlier else rules.so_far
    tempo, reach = max(pace.tempo, 1e-9), max(pace.reach, 1e-3)
    my_tempo, my_reach = tempo / max(mine.tempo, 1e-9), reach / max(mine.reach, 1e-9)
    past = {
        "too fast": max(fast / tempo, own_fast / my_tempo) if tempo < 1.0 else 0.0,
        "too slow": max(tempo / slow, my_tempo / own_slow) if tempo > 1.0 else 0.0,
        "incomplete": max(short / reach, own_short / my_reach),
        "overdone": max(reach / far, my_reach / own_far),
    }
    return sorted(((k, v) for k, v in past.items() if v > 1.0), key=lambda item: -item[1])


def usual_for_patient(kind: str, own: Pace | None, rules: GuidanceRules) -> bool:
    """Whether a guidance type is what this patient usually does (an earlier session's usual
    pace is past the reference's band the same way), so its words may be softer."""
    if own is None or not own.earlier:
        return False
    return kind in dict(pace_guidance(replace(own, earlier=False), None, rules))


def repetition_pace(
    q: FloatArray, mirror_q: FloatArray, reference: FloatArray, tempo: float
) -> tuple[Pace, FloatArray]:
    """A repetition's `Pace` and `reach_series` from its (n, J, 4) rotations of the involved
    joints (and their mirror image's); tempo: its duration over the reference's."""
    series = reach_series(q, mirror_q, reference)
    return Pace(float(tempo), float(series.max()) if series.size else 0.0), series


def guidance(
    alignment: GestureAlignment,
    reach: FloatArray,
    pace: Pace,
    own: Pace | None,
    rules: GuidanceRules,
) -> tuple[Guidance, ...]:
    """Table 1 guidance for one repetition, most pressing first; frames relative to its start.

    reach: (n,) the repetition's `reach_series`; pace: the repetition's; own: the patient's usual
    pace (see `pace_guidance`)."""
    path, n = alignment.path, len(reach)
    fast, slow = _runs(path, rules.min_run)
    frames = {"too fast": _span(fast, n), "too slow": _span(slow, n), "incomplete": _held(path, n)}
    beyond = np.flatnonzero(reach > 1.0)
    frames["overdone"] = (int(beyond[0]), int(beyond[-1])) if beyond.size else (0, n - 1)
    return tuple(Guidance(kind, frames[kind]) for kind, _ in pace_guidance(pace, own, rules))


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
