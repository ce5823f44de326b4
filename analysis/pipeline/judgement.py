"""One judgement per repetition (issue 34): its verdict and the reasons for it, made once from one
set of measurements, by the offline pipeline (`analysis.pipeline.advice_stage.judge_repetitions`)
and by the live aligner (`analysis.live.aligner`) alike, so a patient hears live what the
recording's page later says.

A repetition's measurements (`RepetitionFacts`): its score, its pace (paper 001's tempo and reach,
`analysis.pipeline.gestures.pace_guidance`, with the guidance types that rule gives) and its
clinical angles (`analysis.assessment.findings.RepetitionMeasures`). From them, `judge`:

- ``passed``: the score reaches the pass mark and no plain error (`findings.plainly_off`) fails it;
- ``hits``: its own differences from the demonstration (`findings.findings` on this repetition
  alone, with the tolerances the recording's corrections use, so every correction naming a
  repetition is one of its hits): only in a failed repetition, except the tempo tip;
- ``guidance``: the pace rule's types, one per axis (tempo, reach), leaving out a type that points
  against a hit (never "overdone" beside "raise higher", never "too slow" beside "slow down");
- ``reasons``: the sentences the patient reads: its corrections said for this repetition, then its
  guidance; a failed repetition with neither is told its largest difference from the
  demonstration (`_largest_difference`: an angle the exercise trains or the trunk's posture; else
  how its reach or tempo is off), so it is never told only a score.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

from analysis.assessment.findings import (
    TRUNK,
    Finding,
    Reference,
    RepetitionMeasures,
    findings,
    involved_angles,
    plainly_off,
    swapped_side,
)
from analysis.feedback.advice import fields, say
from analysis.feedback.sentences import Grammar

THIS = "this repetition"  # what a sentence's {repetitions} says of one repetition
MAX_REASONS = 3
GUIDANCE_TEXT = {
    "too fast": "Slow down: take as long as the demonstration.",
    "too slow": "A little faster: keep the demonstration's pace.",
    "overdone": "Not so far: stop where the demonstration stops.",
    "incomplete": "Go further: reach the demonstration's end position.",
}
# the patient's own usual pace is off the demonstration's the same way: the same type, softer
USUAL_TEXT = {
    "too fast": "Quicker than the demonstration, as you usually are: try to take its time.",
    "too slow": "Slower than the demonstration, as you usually are: try to keep its pace.",
    "overdone": "Further than the demonstration, as you usually go: try to stop where it stops.",
    "incomplete": "Short of the demonstration, as you usually are: try to reach its end position.",
}
# the guidance types a correction's kind points against
AGAINST = {
    "less": {"overdone"},
    "more": {"incomplete"},
    "fast": {"too slow"},
    "slow": {"too fast"},
}
AXES = (("too fast", "too slow"), ("incomplete", "overdone"))


@dataclass(frozen=True)
class RepetitionFacts:
    """One repetition's measurements: its 1-based number, score (0–100), the pace rule's guidance
    types (most pressing first) and those the patient's own pace softens, and its clinical angles,
    tempo and reach (`RepetitionMeasures`; its ``passed`` and ``pace`` are set by `judge`)."""

    number: int
    score: float
    guidance: tuple[str, ...]
    measures: RepetitionMeasures
    usual: tuple[str, ...] = ()


@dataclass(frozen=True)
class Judge:
    """What every repetition of a recording is judged against: the demonstration's reference,
    whether the patient used the other side, the pass mark, the exercise's grammar (then the
    default sentences) and the words for the exercise's main part ("both arms")."""

    reference: Reference
    mirrored: bool
    threshold: float
    speakers: tuple[Grammar, ...]
    main_part: str = "body"


@dataclass(frozen=True)
class Judgement:
    """One repetition's verdict, its guidance types, its reasons (sentences) and its hits."""

    passed: bool
    guidance: tuple[str, ...]
    reasons: tuple[str, ...]
    hits: tuple[Finding, ...] = ()


def one_per_axis(types: Sequence[str]) -> tuple[str, ...]:
    """The types, keeping the first (most pressing) of each axis: never fast and slow, never
    incomplete and overdone together."""
    kept: list[str] = []
    for kind in types:
        axis = next((a for a in AXES if kind in a), (kind,))
        if not any(k in axis for k in kept):
            kept.append(kind)
    return tuple(kept)


def judge(facts: RepetitionFacts, judge_: Judge) -> Judgement:
    """The judgement of one repetition (module docstring)."""
    ref, rep = judge_.reference, facts.measures
    guidance = one_per_axis(facts.guidance)
    passed = facts.score >= judge_.threshold and not plainly_off(rep, ref, judge_.mirrored)
    hits = own_hits(replace(rep, passed=passed, pace=guidance), judge_)
    against = set().union(*(AGAINST.get(h.kind, set()) for h in hits if _angle_or_tempo(h)))
    guidance = tuple(g for g in guidance if g not in against)
    told = [USUAL_TEXT[g] if g in facts.usual else GUIDANCE_TEXT[g] for g in guidance]
    reasons = [*_said(hits, facts.number, judge_), *told]
    if not passed and not hits:
        # nothing past its tolerance: the largest difference that agrees with the guidance,
        # after it (so that the recording has a correction naming this repetition)
        nearest = _largest_difference(rep, judge_, guidance)
        hits = [nearest] if nearest is not None else []
        reasons = [*told, *_said(hits, facts.number, judge_)] or [_pace_reason(rep)]
    return Judgement(passed, guidance, tuple(reasons[:MAX_REASONS]), tuple(hits))


def _angle_or_tempo(hit: Finding) -> bool:
    """A hit on an angle the exercise trains (its range) or on tempo: what guidance speaks of."""
    return hit.kind in AGAINST


def own_hits(rep: RepetitionMeasures, judge_: Judge) -> list[Finding]:
    """The repetition's own corrections (`findings` of it alone, corrections only, largest
    first), numbered 1 so that they can be said for it."""
    found = findings([rep], judge_.reference, judge_.mirrored)
    return [f for f in found if f.kind != "good"]


def _said(hits: Sequence[Finding], number: int, judge_: Judge) -> list[str]:
    """The hits in the exercise's words, for this repetition."""
    out = []
    for hit in hits:
        values = {**fields(hit, 1, judge_.main_part), "repetitions": THIS}
        text = next((t for g in judge_.speakers if (t := say(g, hit, values))), None)
        if text:
            out.append(text)
    return out


def _pace_reason(rep: RepetitionMeasures) -> str:
    """The way a repetition's reach or tempo is further off the demonstration's."""
    if rep.reach is not None and abs(rep.reach - 1.0) >= abs(rep.tempo - 1.0):
        return GUIDANCE_TEXT["incomplete" if rep.reach < 1.0 else "overdone"]
    return GUIDANCE_TEXT["too fast" if rep.tempo < 1.0 else "too slow"]


def _largest_difference(
    rep: RepetitionMeasures, judge_: Judge, guidance: Sequence[str] = ()
) -> Finding | None:
    """For a failed repetition with no difference past its tolerance: the involved angle whose
    range is furthest off the demonstration's (relative to it) in a direction the ``guidance``
    does not point against, else the trunk's posture, else its tempo when guided."""
    ref, mirrored = judge_.reference, judge_.mirrored
    chosen = involved_angles(ref.ranges) if ref.involved is None else set(ref.involved)
    best: tuple[float, Finding] | None = None
    for key in sorted(chosen):
        name = swapped_side(key) if mirrored else key
        own, tutor = rep.ranges.get(name), ref.ranges.get(key, 0.0)
        kind = "less" if own is not None and own < tutor else "more"
        if own is None or tutor <= 0 or AGAINST[kind] & set(guidance):
            continue
        found = Finding(kind, name, round(abs(tutor - own), 1), round(tutor, 1), round(own, 1),
                        (1,), rep.start, 1.0)  # fmt: skip
        if best is None or abs(tutor - own) / tutor > best[0]:
            best = (abs(tutor - own) / tutor, found)
    if best is not None:
        return best[1]
    return _posture_difference(rep, ref.middles, mirrored) or _tempo_difference(rep, guidance)


def _tempo_difference(rep: RepetitionMeasures, guidance: Sequence[str]) -> Finding | None:
    """The repetition's tempo as a finding, when the guidance calls it too fast or too slow."""
    kind = "fast" if "too fast" in guidance else "slow" if "too slow" in guidance else ""
    if not kind or (rep.tempo < 1.0) != (kind == "fast"):
        return None
    off = round(100.0 * abs(1.0 - rep.tempo), 1)
    return Finding(kind, "", off, 100.0, round(100.0 * rep.tempo, 1), (1,), rep.start, 1.0)


def _posture_difference(
    rep: RepetitionMeasures, middles: Mapping[str, float], mirrored: bool
) -> Finding | None:
    """The trunk's posture off the demonstration's (``held`` / ``held_back``), if measured."""
    for name in TRUNK:
        if name in middles and name in rep.middles:
            own = -middles[name] if mirrored and name != "trunk_flexion" else middles[name]
            off = rep.middles[name] - own
            kind = "held" if off > 0 else "held_back"
            return Finding(kind, name, round(abs(off), 1), round(own, 1),
                           round(rep.middles[name], 1), (1,), rep.start, 1.0)  # fmt: skip
    return None
