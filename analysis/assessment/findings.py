"""What the patient did differently from the tutor, per recording, in clinical angles and tempo.

The feedback's corrections (`analysis.feedback.advice`) are built from these findings: per
anatomical angle (`analysis.clinical`), each repetition's range (max − min, degrees) against the
median range of the tutor's repetitions, each repetition's posture (the middle of its range)
against the tutor's, and each repetition's duration against the tutor's.

Only what the exercise trains is corrected (issue 26): the *involved* angles are those the tutor
moves at least `INVOLVED_SHARE` of its most-moved angle (and `MOVED_DEG`), one per joint (the
shoulder's flexion, abduction and elevation are one arm: its elevation speaks for it when moved
that much, else the angle the tutor moves most), repeated alike from one repetition to the
next (`unsteady_angles`: not the other arm a tutor swings), narrowed to the joints the therapist
ticked when any is among them (`involved_angles`). So a part is never both "as far as the
demonstration" and "too little", and a squat's arms, swung for balance, are not corrected.
Compensations are the trunk's: its lean held through the movement (posture) and its movement
where the tutor keeps it still; and those `analysis.assessment.compensations` measures from
positions (rotation, shoulder hike, knee valgus), passed in as further "angles".

Each angle's tolerance is its own: max(`TOLERANCE_DEG`, `SPREAD_FACTOR` × the spread of its range
over the tutor's repetitions, `TOLERANCE_SHARE` of the tutor's range). A noisy angle (a Kinect
ankle whose range wanders by 20° between the tutor's own repetitions) gets a wide one.

- ``less``: an involved angle covers less than the tutor's range minus the tolerance; the amount
  is the loss in the patient's excursion (tutor's range − the patient's, degrees of that angle).
- ``more``: an involved angle covers more than the tutor's range plus the tolerance.
- ``extra``: the trunk moves by more than max(`EXTRA_DEG`, `SPREAD_FACTOR` × spread) beyond the
  tutor's range where the tutor keeps it (nearly) still (leaning in a shoulder raise); or a
  compensation of `analysis.assessment.compensations` (the trunk turning, a shoulder hiked, a
  knee falling inward) ranges beyond the tutor's by more than its own limit.
- ``held`` / ``held_back``: the trunk's posture over a repetition (the middle of its range) is
  more than `HELD_DEG` off the tutor's, forward (or to the right) / backward (to the left): a lean
  held all through, which a range does not show.
- ``fast`` / ``slow``: paper 001's pace rule called the repetition "too fast" / "too slow"
  (`analysis.pipeline.gestures.pace_guidance`: against the tutor's pace and, when an earlier
  session gave it, the patient's own; the same rule live), or a failed repetition lasts less than
  `FAST_BELOW` or more than `SLOW_ABOVE` times the tutor's. Pace is not part of the score, so a
  passed recording is still told its tempo (a tip, in percent, never an angle).
- ``good``: an involved angle that no repetition got wrong: what went well.

Feedback agrees with the score, both ways. A plain error fails its repetition whatever its score
(`plainly_off`, applied by `analysis.pipeline.advice_stage`): a main angle (an involved one the
tutor moves at least `MAIN_SHARE` as far as its most-moved) covering less than `PLAIN_SHARE` of the
tutor's range in a repetition short of `PLAIN_REACH` along the movement, or the trunk held more
than `PLAIN_LEAN_DEG` off the tutor's posture. And a difference counts only in a repetition that
did not pass, and a recording that passed is told at most small tips (below `SMALL_DEG`; with the
tolerances above, that is no angle correction at all) and its tempo. A finding counts when it
happens in at least `MIN_SHARE` of the repetitions; its amount is the median difference over those
repetitions. Corrections are ranked the angles' first (the involved ones and the trunk's), then the
compensations measured from positions (noisier), then tempo, each by size (degrees off times how
often): only involved angles, the trunk and the compensations are ever corrected. Ranges and
postures, not single values, are compared; a one-sided exercise done with the other side is
compared side for side (``mirrored``). Thresholds are wide on purpose (goniometer repeatability is
5–10°, Kinect-class joint angles wander more).
"""

from __future__ import annotations

import statistics
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from analysis.assessment.compensations import limit_of
from analysis.assessment.trainable import trainable

MOVED_DEG = 20.0
INVOLVED_SHARE = 0.6  # of the tutor's most-moved angle: an angle the exercise trains
TOLERANCE_DEG = 15.0
TOLERANCE_SHARE = 0.3
EXTRA_DEG = 20.0
MAIN_SHARE = 0.8  # of the involved angles' largest tutor range: a main angle of the exercise
PLAIN_SHARE = 0.7  # a main angle covering less of the tutor's range fails its repetition
PLAIN_REACH = 0.75  # ... in a repetition that went less of the way along the movement
PLAIN_LEAN_DEG = 15.0  # so does the trunk held further off the tutor's posture
HELD_DEG = 12.0  # the trunk's posture off the tutor's by more: a lean held all through
SMALL_DEG = 10.0  # a recording that passed is told only differences below this (° or %)
FAST_BELOW, SLOW_ABOVE = 0.6, 1.8
MIN_SHARE = 0.4
TIPS = ("good", "fast", "slow")  # said whether the recording passed or not
SPREAD_FACTOR = 2.0  # times the tutor's own spread (SD of the range over its repetitions)
TRUNK = ("trunk_flexion", "trunk_lateral_flexion")
UNSTEADY_SHARE = 0.22  # a range wandering more between the tutor's repetitions: not trained
ARM_JOINTS, LEG_JOINTS = ("shoulder", "elbow", "wrist"), ("hip", "knee", "ankle")
PREFERRED = "shoulder_elevation"  # speaks for the arm when moved: the arm's angle to the trunk
KINDS = ("less", "more", "extra", "held", "held_back", "fast", "slow", "good")


@dataclass(frozen=True)
class RepetitionMeasures:
    """One repetition of the recording: its first frame, each angle's range (degrees), its
    duration over the tutor's (tempo), whether its score passed, each angle's posture (the
    middle of its range, degrees) and how far it went along the movement (None: unknown)."""

    start: int
    ranges: Mapping[str, float]
    tempo: float
    passed: bool = False
    middles: Mapping[str, float] = field(default_factory=dict)
    reach: float | None = None  # along the exercise's progress axis, 1 = as far as the tutor
    pace: Collection[str] = ()  # paper 001's guidance types of the repetition ("too fast"…)


@dataclass(frozen=True)
class Reference:
    """What the tutor does, per angle: the median range over its repetitions, that range's SD
    (``spread``), the median posture (``middles``), and the angles the exercise trains
    (``involved``; None: `involved_angles` of the ranges); ``moved``: those the tutor moves
    most whether it repeats them alike or not (`involved_angles` without the spread), which a
    plain error is judged on (None: ``involved``)."""

    ranges: Mapping[str, float]
    spread: Mapping[str, float] = field(default_factory=dict)
    middles: Mapping[str, float] = field(default_factory=dict)
    involved: Collection[str] | None = None
    moved: Collection[str] | None = None


@dataclass(frozen=True)
class Finding:
    """One difference from the tutor over the recording (see the module docstring).

    ``angle``: the clinical angle on the patient's own side ("" for tempo); ``amount``: degrees
    (angles) or percent of the tutor's duration off (tempo); ``tutor`` / ``patient``: the tutor's
    range and the patient's median range (degrees; postures for ``held``), or durations in
    percent of the tutor's (tempo); ``repetitions``: 1-based numbers where it happened;
    ``frame``: the first one's start.
    """

    kind: str
    angle: str
    amount: float
    tutor: float
    patient: float
    repetitions: tuple[int, ...]
    frame: int
    share: float

    @property
    def percent(self) -> float:
        """The patient's range (or duration) in percent of the tutor's."""
        return 100.0 * self.patient / self.tutor if self.tutor > 0 else 0.0

    @property
    def weight(self) -> float:
        """How much it matters, to rank corrections: degrees off times how often (a tempo
        off by half counts as 30°)."""
        size = self.amount if self.angle else 0.6 * self.amount
        return size * self.share


def swapped_side(name: str) -> str:
    """The same angle on the other side ("knee_flexion_left" → "knee_flexion_right")."""
    if name.endswith("_left"):
        return name[:-5] + "_right"
    if name.endswith("_right"):
        return name[:-6] + "_left"
    return name


def joint_of(name: str) -> str:
    """The joint an angle belongs to: "shoulder_left" for "shoulder_elevation_left", "trunk"."""
    side = next((s for s in ("_left", "_right") if name.endswith(s)), "")
    return name.split("_", maxsplit=1)[0] + side


def limb_of(name: str) -> str:
    """The limb an angle belongs to: "arm_left" for the shoulder's and elbow's left angles,
    "leg_right" for the hip's, knee's and ankle's right ones, else its joint ("trunk")."""
    joint, _, side = joint_of(name).partition("_")
    kind = "arm" if joint in ARM_JOINTS else "leg" if joint in LEG_JOINTS else joint
    return f"{kind}_{side}" if side else kind


def unsteady_angles(tutor: Mapping[str, float], spread: Mapping[str, float]) -> set[str]:
    """The angles the tutor moves far (past the involved limit) but differently in every
    repetition: the range wanders (SD over the tutor's repetitions) by more than
    `UNSTEADY_SHARE` of it; and every angle of a limb with no steadier one. A movement the
    exercise trains is repeated as taught (UI-PRMD m08's tutor swings its other arm, elbow
    93° ± 22°, while the trained arm repeats 66° ± 4°; m04's ankle wanders 63° ± 18° under a hip
    that repeats 103° ± 3°). Never every moved angle: with no steady one, none is left out."""
    top = max(tutor.values(), default=0.0)
    limit = max(MOVED_DEG, INVOLVED_SHARE * top)
    moved = {n for n, v in tutor.items() if v >= limit}
    wander = {n for n in moved if spread.get(n, 0.0) > UNSTEADY_SHARE * tutor[n]}
    if wander == moved:
        return set()
    steady_limbs = {limb_of(n) for n in moved - wander}
    return wander | {n for n in tutor if limb_of(n) not in steady_limbs and limb_of(n) in
                     {limb_of(m) for m in moved}}  # fmt: skip


def involved_angles(
    tutor: Mapping[str, float],
    ticked: Collection[str] = (),
    spread: Mapping[str, float] | None = None,
) -> set[str]:
    """The angles the exercise trains (module docstring): moved by the tutor at least
    `INVOLVED_SHARE` of its most-moved angle, one per joint (the shoulder's elevation when it is
    moved that much, else the joint's most-moved angle), leaving out what the tutor does not
    repeat the same in every repetition (`unsteady_angles`, from ``spread``: the SD of each
    range over the tutor's repetitions); ``ticked``: joints ("knee_left", "shoulder_right",
    `joint_of`) the therapist chose, which narrow the set when any of them is in it."""
    tutor = trainable(tutor)  # not the arm's direction of raising, its roll only in m09-like
    unsteady = unsteady_angles(tutor, spread or {})
    tutor = {n: v for n, v in tutor.items() if n not in unsteady}
    top = max(tutor.values(), default=0.0)
    limit = max(MOVED_DEG, INVOLVED_SHARE * top)
    best: dict[str, str] = {}
    for name, value in sorted(tutor.items(), key=lambda item: (PREFERRED in item[0], item[1])):
        if value >= limit:
            best[joint_of(name)] = name  # the last: the preferred angle, else the most moved
    narrowed = {n for j, n in best.items() if j in ticked}
    return narrowed or set(best.values())


def main_angles(ref: Reference) -> set[str]:
    """The angles a plain error is judged on: of ``ref.moved`` (else the involved ones), those
    the tutor moves at least `MAIN_SHARE` as far as its most-moved one. Not narrowed to what the
    tutor repeats alike: the cold-start distance score weighs every joint the tutor moves, and
    judged on the repeated angles alone, UI-PRMD m08's repetition AUC fell from 0.886 to 0.853
    and one more of its sessions disagreed with its label (docs/sections/eval_mistakes.md)."""
    chosen = set(ref.moved) if ref.moved is not None else (
        involved_angles(ref.ranges) if ref.involved is None else set(ref.involved))  # fmt: skip
    top = max((ref.ranges.get(n, 0.0) for n in chosen), default=0.0)
    return {n for n in chosen if ref.ranges.get(n, 0.0) >= MAIN_SHARE * top}


def plainly_off(rep: RepetitionMeasures, ref: Reference, mirrored: bool = False) -> bool:
    """Whether a repetition's error is plain to see whatever its score: a main angle covering
    less than `PLAIN_SHARE` of the tutor's range (55 % of an excursion) in a repetition that also
    went less than `PLAIN_REACH` of the way along the movement (when known: a tutor's angle the
    patient need not copy, e.g. a bent elbow in a shoulder extension, fails nobody who went all
    the way), or the trunk held more than `PLAIN_LEAN_DEG` off the tutor's posture (a 20° lean)."""
    short_of_it = rep.reach is None or rep.reach < PLAIN_REACH
    for name in main_angles(ref) if short_of_it else ():
        own = rep.ranges.get(swapped_side(name) if mirrored else name)
        if own is not None and own < PLAIN_SHARE * ref.ranges[name]:
            return True
    for name in TRUNK:
        if name in ref.middles and name in rep.middles:
            tutor = (
                -ref.middles[name] if mirrored and name != "trunk_flexion" else ref.middles[name]
            )
            if abs(rep.middles[name] - tutor) > PLAIN_LEAN_DEG:
                return True
    return False


def _finding(kind: str, angle: str, tutor: float, hits: list[tuple[int, float, float]],
             total: int) -> Finding | None:  # fmt: skip
    """A finding from its (repetition index, amount, patient value) hits, if frequent enough.
    Hits are never NaN (a NaN is beyond no tolerance): `statistics.median` is numpy's value."""
    if not hits or len(hits) < MIN_SHARE * total:
        return None
    return Finding(
        kind, angle, round(float(statistics.median([h[1] for h in hits])), 1), round(tutor, 1),
        round(float(statistics.median([h[2] for h in hits])), 1), tuple(h[0] + 1 for h in hits),
        -1, len(hits) / total,
    )  # fmt: skip


def _off(reps: Sequence[RepetitionMeasures], k: int, difference: float, tolerance: float) -> bool:
    """Whether repetition k's difference counts: beyond the tolerance, in a failed repetition."""
    return difference > tolerance and not reps[k].passed


def _range_findings(reps: Sequence[RepetitionMeasures], name: str, own: float,
                    tolerance: float) -> list[Finding | None]:  # fmt: skip
    """``less`` / ``more`` / ``good`` of one involved angle (its tutor range ``own``)."""
    values = [(k, r.ranges[name]) for k, r in enumerate(reps) if name in r.ranges]
    less = [(k, own - v, v) for k, v in values if _off(reps, k, own - v, tolerance)]
    more = [(k, v - own, v) for k, v in values if _off(reps, k, v - own, tolerance)]
    found = [_finding("less", name, own, less, len(reps)),
             _finding("more", name, own, more, len(reps))]  # fmt: skip
    if all(abs(v - own) <= tolerance for _, v in values):  # passed or not
        found.append(_finding("good", name, own, [(k, abs(v - own), v) for k, v in values],
                              len(reps)))  # fmt: skip
    return found


def angle_findings(
    reps: Sequence[RepetitionMeasures],
    tutor: Mapping[str, float],
    mirrored: bool = False,
    spread: Mapping[str, float] | None = None,
    involved: Collection[str] | None = None,
) -> list[Finding]:
    """Findings of the involved angles and the trunk's movement (module docstring);
    ``spread``: the SD of each angle's range over the tutor's repetitions (0 when unknown);
    ``involved``: the angles the exercise trains, tutor's side (None: `involved_angles`)."""
    chosen = involved_angles(tutor) if involved is None else set(involved)
    out: list[Finding | None] = []
    for name in sorted({n for r in reps for n in r.ranges}):
        key = swapped_side(name) if mirrored else name
        own = tutor.get(key)
        if own is None:
            continue
        wander = SPREAD_FACTOR * (spread or {}).get(key, 0.0)
        if key in chosen:
            out += _range_findings(reps, name, own, max(TOLERANCE_DEG, wander,
                                                         TOLERANCE_SHARE * own))  # fmt: skip
        elif (key in TRUNK and own < MOVED_DEG) or limit_of(key) is not None:
            limit = max(limit_of(key) or EXTRA_DEG, wander)
            values = [(k, r.ranges[name]) for k, r in enumerate(reps) if name in r.ranges]
            extra = [(k, v - own, v) for k, v in values if _off(reps, k, v - own, limit)]
            out.append(_finding("extra", name, own, extra, len(reps)))
    return [f for f in out if f is not None]


def posture_findings(
    reps: Sequence[RepetitionMeasures], middles: Mapping[str, float], mirrored: bool = False
) -> list[Finding]:
    """A trunk lean held through the movement (``held``: forward or to the right, ``held_back``:
    backward or to the left), the repetitions' postures against the tutor's ``middles``."""
    out: list[Finding | None] = []
    for name in TRUNK:
        if name not in middles:
            continue
        own = -middles[name] if mirrored and name == "trunk_lateral_flexion" else middles[name]
        values = [(k, r.middles[name] - own, r.middles[name]) for k, r in enumerate(reps)
                  if name in r.middles]  # fmt: skip
        ahead = [(k, d, v) for k, d, v in values if _off(reps, k, d, HELD_DEG)]
        behind = [(k, -d, v) for k, d, v in values if _off(reps, k, -d, HELD_DEG)]
        out += [_finding("held", name, own, ahead, len(reps)),
                _finding("held_back", name, own, behind, len(reps))]  # fmt: skip
    return [f for f in out if f is not None]


def _paced(rep: RepetitionMeasures, guidance: str, far_off: bool) -> bool:
    """The pace rule gave the repetition this guidance, or it failed far off the tutor's pace."""
    return guidance in rep.pace or (far_off and not rep.passed)


def tempo_findings(reps: Sequence[RepetitionMeasures]) -> list[Finding]:
    """Too fast or too slow: by the pace rule, or a failed repetition far off the tutor's
    duration (module docstring). The amount is against the tutor's duration, so a repetition
    the rule finds too fast for the patient's own pace but still slower than the tutor's is not
    told to slow down (the sentence could not be true)."""
    fast = [(k, 100.0 * (1 - r.tempo), 100.0 * r.tempo) for k, r in enumerate(reps)
            if r.tempo < 1.0 and _paced(r, "too fast", r.tempo < FAST_BELOW)]  # fmt: skip
    slow = [(k, 100.0 * (r.tempo - 1), 100.0 * r.tempo) for k, r in enumerate(reps)
            if r.tempo > 1.0 and _paced(r, "too slow", r.tempo > SLOW_ABOVE)]  # fmt: skip
    found = [_finding("fast", "", 100.0, fast, len(reps)),
             _finding("slow", "", 100.0, slow, len(reps))]  # fmt: skip
    return [f for f in found if f is not None]


def findings(
    reps: Sequence[RepetitionMeasures],
    tutor: Mapping[str, float] | Reference,
    mirrored: bool = False,
    spread: Mapping[str, float] | None = None,
    *,
    passed: bool = False,
    extra: Sequence[Finding] = (),
) -> list[Finding]:
    """Every finding of the recording, corrections first by weight, then what went well; each
    with the frame where its first repetition starts. ``tutor``: a `Reference` (or only its
    ranges, with ``spread``: see `angle_findings`); ``passed``: the recording passed, so only
    corrections below `SMALL_DEG` are kept; ``extra``: compensations found elsewhere
    (`analysis.assessment.compensations`)."""
    if not reps:
        return []
    ref = tutor if isinstance(tutor, Reference) else Reference(tutor, spread or {})
    found = [
        *angle_findings(reps, ref.ranges, mirrored, ref.spread, ref.involved),
        *posture_findings(reps, ref.middles, mirrored), *extra, *tempo_findings(reps),
    ]  # fmt: skip
    kept = [f for f in found if f.kind in TIPS or not passed or f.amount < SMALL_DEG]
    placed = [
        Finding(f.kind, f.angle, f.amount, f.tutor, f.patient, f.repetitions,
                reps[f.repetitions[0] - 1].start, f.share)
        for f in kept
    ]  # fmt: skip
    return sorted(placed, key=_rank)


def _rank(f: Finding) -> tuple[int, float]:
    """Corrections first: the angles' (the involved ones', the trunk's), then the compensations
    measured from positions, then tempo, each by weight; then what went well, largest first."""
    if f.kind == "good":
        return 3, -f.tutor
    return (2 if not f.angle else 1 if limit_of(f.angle) is not None else 0), -f.weight


def tutor_ranges(per_repetition: Sequence[Mapping[str, float]]) -> dict[str, float]:
    """The median of each angle's value (range, or posture) over the tutor's repetitions."""
    names = {n for r in per_repetition for n in r}
    return {n: float(np.median([r[n] for r in per_repetition if n in r])) for n in names}


def tutor_spreads(per_repetition: Sequence[Mapping[str, float]]) -> dict[str, float]:
    """The SD (degrees) of each angle's range over the tutor's repetitions (0 for one)."""
    names = {n for r in per_repetition for n in r}
    return {n: float(np.std([r[n] for r in per_repetition if n in r])) for n in names}
