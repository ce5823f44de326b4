"""Corrections a patient can act on: the few most important differences of a recording, in words.

`advise(grammar, findings)` takes the findings of `analysis.assessment.findings` (largest first)
and lets the exercise's grammar say each one: the first rule whose ``%KIND$ANGLE`` condition holds
gives the sentence, its ``{…}`` fields filled with the finding's figures. At most
`MAX_CORRECTIONS` corrections, each naming the body part, the direction (raise, lower, bend,
straighten, lean, keep still, slow down, speed up) and the amount (degrees, or percent of the
tutor's time), with the repetitions where it happened; and up to `MAX_WELL` things that went well.
A grammar without ``%`` rules (written before corrections existed) is said with the default ones.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from analysis.assessment.findings import Finding
from analysis.clinical.labels import INSTRUCTIONS, STILL_INSTRUCTION, angle_part, split_side
from analysis.feedback.sentences import Grammar

MAX_CORRECTIONS = 5
MAX_WELL = 3
TEMPO_DIRECTIONS = {"fast": "slow down", "slow": "speed up"}
HELD_DIRECTIONS = {"held": "straighten", "held_back": "lean"}  # a trunk lean held all through


@dataclass(frozen=True)
class Correction:
    """One correction: its sentence, and what it says in fields (for pages and tests)."""

    text: str
    part: str  # plain words: "left arm", "trunk"
    direction: str  # "raise", "lower", "bend", "straighten", "lean", "keep still", "slow down"…
    amount: float
    unit: str  # "°" or "%"
    repetitions: tuple[int, ...]  # 1-based
    frame: int  # where the first of those repetitions starts
    angle: str = ""  # the clinical angle it speaks of ("" for tempo), for evaluations

    def to_json(self) -> dict[str, Any]:
        return {
            "text": self.text, "part": self.part, "direction": self.direction,
            "amount": self.amount, "unit": self.unit, "repetitions": list(self.repetitions),
            "frame": self.frame, "angle": self.angle,
        }  # fmt: skip

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Correction:
        return cls(
            str(data.get("text", "")), str(data.get("part", "")),
            str(data.get("direction", "")), float(data.get("amount", 0.0)),
            str(data.get("unit", "")), tuple(int(r) for r in data.get("repetitions", ())),
            int(data.get("frame", 0)), str(data.get("angle", "")),
        )  # fmt: skip


@dataclass(frozen=True)
class Advice:
    """The corrections of a recording, most important first, and what went well."""

    corrections: tuple[Correction, ...] = ()
    went_well: tuple[str, ...] = ()

    def to_json(self) -> dict[str, Any]:
        return {
            "corrections": [c.to_json() for c in self.corrections],
            "went_well": list(self.went_well),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any] | None) -> Advice:
        data = data or {}
        return cls(
            tuple(Correction.from_json(c) for c in data.get("corrections", ())),
            tuple(str(t) for t in data.get("went_well", ())),
        )


def repetition_words(numbers: Sequence[int], total: int) -> str:
    """ "every repetition", "repetition 3", "repetitions 1, 2 and 5"."""
    if total > 1 and len(numbers) == total:
        return "every repetition"
    if len(numbers) == 1:
        return f"repetition {numbers[0]}"
    return "repetitions " + ", ".join(map(str, numbers[:-1])) + f" and {numbers[-1]}"


def direction_of(finding: Finding) -> str:
    if not finding.angle:
        return TEMPO_DIRECTIONS.get(finding.kind, "")
    if finding.kind == "extra":
        return STILL_INSTRUCTION[0]
    if finding.kind in HELD_DIRECTIONS:
        return HELD_DIRECTIONS[finding.kind] if finding.angle == "trunk_flexion" else "straighten"
    return INSTRUCTIONS.get((split_side(finding.angle)[0], finding.kind), ("", ""))[0]


def fields(finding: Finding, total: int, main_part: str) -> dict[str, str]:
    """The values of a sentence's ``{…}`` fields for one finding."""
    unit = "°" if finding.angle else " %"
    return {
        "part": angle_part(finding.angle) if finding.angle else main_part,
        "amount": f"{finding.amount:.0f}{unit}",
        "patient": f"{finding.patient:.0f}{unit}",
        "tutor": f"{finding.tutor:.0f}{unit}",
        "percent": f"{finding.percent:.0f} %",
        "repetitions": repetition_words(finding.repetitions, total),
    }


def say(grammar: Grammar, finding: Finding, values: Mapping[str, str]) -> str | None:
    """The grammar's sentence for a finding, fields filled; None when no rule speaks of it."""
    found = grammar.match(-1, {}, (finding.kind, finding.angle)).feedbacks
    if not found:
        return None
    text = found[0].format_map(_Fields(values))
    return text if text.endswith((".", "!", "?")) else text + "."


class _Fields(dict[str, str]):
    """Unknown ``{name}`` fields stay as written, so a typo in a grammar shows, never fails."""

    def __missing__(self, key: str) -> str:
        return "{" + key + "}"


def advise(
    grammar: Grammar,
    findings: Sequence[Finding],
    total: int,
    main_part: str = "body",
    fallback: Grammar | None = None,
) -> Advice:
    """Up to `MAX_CORRECTIONS` corrections and `MAX_WELL` things that went well (module
    docstring); ``total``: the number of repetitions; ``main_part``: what tempo findings name;
    ``fallback``: the grammar that says what ``grammar`` has no rule for."""
    speakers = [g for g in (grammar, fallback) if g is not None]
    corrections: list[Correction] = []
    well: list[str] = []
    for finding in findings:
        values = fields(finding, total, main_part)
        text = next((t for g in speakers if (t := say(g, finding, values))), None)
        if text is None:
            continue
        if finding.kind == "good":
            if len(well) < MAX_WELL:
                well.append(text)
        elif len(corrections) < MAX_CORRECTIONS:
            unit = "°" if finding.angle else "%"
            corrections.append(Correction(
                text, values["part"], direction_of(finding), finding.amount, unit,
                finding.repetitions, finding.frame, finding.angle,
            ))  # fmt: skip
    return Advice(tuple(corrections), tuple(well))
