"""What the patient did differently from the tutor, per recording, in clinical angles and tempo.

The feedback's corrections (`analysis.feedback.advice`) are built from these findings: per
anatomical angle (`analysis.clinical`), each repetition's range (max − min, degrees) against the
median range of the tutor's repetitions, and each repetition's duration against the tutor's.

Each angle's tolerance is its own: max(`TOLERANCE_DEG`, `SPREAD_FACTOR` × the spread of its range
over the tutor's repetitions, `TOLERANCE_SHARE` of the tutor's range). A noisy angle (a Kinect
ankle whose range wanders by 20° between the tutor's own repetitions) gets a wide one.

- ``less``: the tutor moves the angle (range ≥ `MOVED_DEG`) and a repetition covers less than
  the tutor's range minus the tolerance.
- ``more``: a repetition covers more than the tutor's range plus the tolerance.
- ``extra``: the tutor keeps the angle (nearly) still and a repetition moves it by more than
  max(`EXTRA_DEG`, `SPREAD_FACTOR` × spread) beyond the tutor's range (a compensation: the trunk
  leaning in a shoulder raise).
- ``fast`` / ``slow``: a repetition lasts less than `FAST_BELOW` or more than `SLOW_ABOVE`
  times the tutor's.
- ``good``: an angle the tutor moves that no repetition got wrong: what went well.

Feedback agrees with the score: a difference counts in a repetition that did not pass; in one that
passed only when it is `PLAIN_FACTOR` times the tolerance (plain to see whatever the score), and
tempo not at all. Between-subject differences in angles the score does not weigh (how far a
healthy person lifts the arms in a squat) then stop being corrections of good repetitions: on
UI-PRMD, 87 % of correct sessions get at most one correction, 82 % of incorrect ones at least one.
A finding counts when it happens in at least `MIN_SHARE` of the repetitions (one of two is
enough); its amount is the median difference over those repetitions; corrections are ranked by
size (degrees off times how often). Ranges, not single values,
are compared: where the patient stands and how the rig zeroes an angle do not matter, and a
one-sided exercise done with the other side is compared side for side (``mirrored``).
Thresholds are wide on purpose (goniometer repeatability is 5–10°, Kinect-class joint angles
wander more): a correction is worth giving only when the difference is plain to see.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

MOVED_DEG = 20.0
TOLERANCE_DEG = 15.0
TOLERANCE_SHARE = 0.3
EXTRA_DEG = 20.0
FAST_BELOW, SLOW_ABOVE = 0.6, 1.8
MIN_SHARE = 0.4
SPREAD_FACTOR = 2.0  # times the tutor's own spread (SD of the range over its repetitions)
PLAIN_FACTOR = 3.0  # times the tolerance: said even for a repetition that passed
KINDS = ("less", "more", "extra", "fast", "slow", "good")


@dataclass(frozen=True)
class RepetitionMeasures:
    """One repetition of the recording: its first frame, each angle's range (degrees), its
    duration over the tutor's (tempo) and whether its score passed."""

    start: int
    ranges: Mapping[str, float]
    tempo: float
    passed: bool = False


@dataclass(frozen=True)
class Finding:
    """One difference from the tutor over the recording (see the module docstring).

    ``angle``: the clinical angle on the patient's own side ("" for tempo); ``amount``: degrees
    (angles) or percent of the tutor's duration off (tempo); ``tutor`` / ``patient``: the tutor's
    range and the patient's median range (degrees), or durations in percent of the tutor's
    (tempo); ``repetitions``: 1-based numbers where it happened; ``frame``: the first one's start.
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


def _finding(kind: str, angle: str, tutor: float, hits: list[tuple[int, float, float]],
             total: int) -> Finding | None:  # fmt: skip
    """A finding from its (repetition index, amount, patient value) hits, if frequent enough."""
    if not hits or len(hits) < MIN_SHARE * total:
        return None
    return Finding(
        kind, angle, round(float(np.median([h[1] for h in hits])), 1), round(tutor, 1),
        round(float(np.median([h[2] for h in hits])), 1), tuple(h[0] + 1 for h in hits),
        -1, len(hits) / total,
    )  # fmt: skip


def _off(reps: Sequence[RepetitionMeasures], k: int, difference: float, tolerance: float) -> bool:
    """Whether repetition k's difference counts (module docstring: it agrees with the score)."""
    return difference > tolerance * (PLAIN_FACTOR if reps[k].passed else 1.0)


def angle_findings(
    reps: Sequence[RepetitionMeasures],
    tutor: Mapping[str, float],
    mirrored: bool = False,
    spread: Mapping[str, float] | None = None,
) -> list[Finding]:
    """Findings of every angle both the recording and the tutor have (module docstring);
    ``spread``: the SD of each angle's range over the tutor's repetitions (0 when unknown)."""
    out: list[Finding] = []
    for name in sorted({n for r in reps for n in r.ranges}):
        key = swapped_side(name) if mirrored else name
        own = tutor.get(key)
        if own is None:
            continue
        values = [(k, r.ranges[name]) for k, r in enumerate(reps) if name in r.ranges]
        wander = SPREAD_FACTOR * (spread or {}).get(key, 0.0)
        tolerance = max(TOLERANCE_DEG, wander, TOLERANCE_SHARE * own)
        if own >= MOVED_DEG:
            less = [(k, own - v, v) for k, v in values if _off(reps, k, own - v, tolerance)]
            more = [(k, v - own, v) for k, v in values if _off(reps, k, v - own, tolerance)]
            found = [_finding("less", name, own, less, len(reps)),
                     _finding("more", name, own, more, len(reps))]  # fmt: skip
            if all(abs(v - own) <= tolerance for _, v in values):  # passed or not
                good = [(k, abs(v - own), v) for k, v in values]
                found.append(_finding("good", name, own, good, len(reps)))
        else:
            limit = max(EXTRA_DEG, wander)
            extra = [(k, v - own, v) for k, v in values if _off(reps, k, v - own, limit)]
            found = [_finding("extra", name, own, extra, len(reps))]
        out += [f for f in found if f is not None]
    return out


def tempo_findings(reps: Sequence[RepetitionMeasures]) -> list[Finding]:
    """Too fast or too slow against the tutor's duration (module docstring)."""
    fast = [(k, 100.0 * (1 - r.tempo), 100.0 * r.tempo) for k, r in enumerate(reps)
            if r.tempo < FAST_BELOW and not r.passed]  # fmt: skip
    slow = [(k, 100.0 * (r.tempo - 1), 100.0 * r.tempo) for k, r in enumerate(reps)
            if r.tempo > SLOW_ABOVE and not r.passed]  # fmt: skip
    found = [_finding("fast", "", 100.0, fast, len(reps)),
             _finding("slow", "", 100.0, slow, len(reps))]  # fmt: skip
    return [f for f in found if f is not None]


def findings(
    reps: Sequence[RepetitionMeasures],
    tutor: Mapping[str, float],
    mirrored: bool = False,
    spread: Mapping[str, float] | None = None,
) -> list[Finding]:
    """Every finding of the recording, corrections first by weight, then what went well; each
    with the frame where its first repetition starts (``spread``: see `angle_findings`)."""
    if not reps:
        return []
    found = angle_findings(reps, tutor, mirrored, spread) + tempo_findings(reps)
    placed = [
        Finding(f.kind, f.angle, f.amount, f.tutor, f.patient, f.repetitions,
                reps[f.repetitions[0] - 1].start, f.share)
        for f in found
    ]  # fmt: skip
    return sorted(placed, key=lambda f: (f.kind == "good", -f.weight if f.kind != "good" else
                                         -f.tutor))  # fmt: skip


def tutor_ranges(per_repetition: Sequence[Mapping[str, float]]) -> dict[str, float]:
    """The median range (degrees) of each angle over the tutor's repetitions."""
    names = {n for r in per_repetition for n in r}
    return {n: float(np.median([r[n] for r in per_repetition if n in r])) for n in names}


def tutor_spreads(per_repetition: Sequence[Mapping[str, float]]) -> dict[str, float]:
    """The SD (degrees) of each angle's range over the tutor's repetitions (0 for one)."""
    names = {n for r in per_repetition for n in r}
    return {n: float(np.std([r[n] for r in per_repetition if n in r])) for n in names}
