"""Feedback in words from assessed landmarks (thesis 004 §7.2.4, Algorithms 8–10, Appendix E).

An exercise's *assessment grammar* (syntax in :mod:`analysis.feedback.grammar`) lists rules such as
``type$2 & @LEFT_KNEE$3 -> F:"Your left knee needs to be bent much more", T:"Try ducking lower"``.
For every assessed landmark (frame, landmark type, level per joint) the rules whose condition holds
give feedback texts and tips (Algs 8–9); :meth:`Grammar.comments` turns them into one spoken
comment per landmark, with varied connectives, saying each tip once per session (Alg 10)::

    grammar = Grammar.parse(text)
    comments = grammar.comments([LandmarkAssessment(92, 2, {"LEFT_SHOULDER": 4, ...}), ...])
    comments[0].text  # "On this occasion, you are not rising your left arm. Furthermore, …"

Joints are matched by name, or else by their readable form (:func:`joint_label`), so a grammar
saying ``@LEFT_KNEE$3`` also applies to a skeleton whose joint is called ``LeftKnee``.
Alg. 10's replay loop (paint frames, ask "Do you want me to repeat?") belongs to the user interface.
"""

from __future__ import annotations

from collections.abc import Collection, Iterator, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

from analysis.assessment.findings import KINDS
from analysis.feedback.grammar import (
    And,
    Condition,
    FindingIs,
    GrammarError,
    JointLevel,
    LandmarkType,
    Not,
    Or,
    Rule,
    format_rule,
    parse_rules,
)
from analysis.feedback.text import (
    Chooser,
    FeedbackOptions,
    VariedChooser,
    compose_feedback,
    compose_tips,
    default_grammar,
    joint_label,
)

__all__ = [
    "Comment",
    "FeedbackOptions",
    "Grammar",
    "GrammarError",
    "LandmarkAssessment",
    "Match",
    "Rule",
    "default_grammar",
    "joint_label",
    "matches",
]

_key = cache(joint_label)


@dataclass(frozen=True)
class LandmarkAssessment:
    """One assessed landmark: frame, landmark type, level per joint (1 = as the tutor … 4 worst)."""

    frame: int
    type: int
    levels: Mapping[str, int]

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> LandmarkAssessment:
        """From the ``assessment`` items of ``analyse --json``: {"frame", "type", "levels"}."""
        levels = {str(j): int(v) for j, v in dict(data["levels"]).items()}
        return cls(int(data["frame"]), int(data["type"]), levels)


@dataclass(frozen=True)
class Comment:
    """What is said at one landmark: ``text`` = ``feedback`` sentences, then the new ``tip``."""

    frame: int
    text: str
    tip: str = ""
    feedback: str = ""

    def to_dict(self) -> dict[str, Any]:
        """The ``feedback`` items of ``analyse --json``."""
        return {"frame": self.frame, "text": self.text, "tip": self.tip}


@dataclass(frozen=True)
class Match:
    """Feedback texts and tips of the rules matching one landmark, in grammar order, no repeats."""

    feedbacks: tuple[str, ...]
    tips: tuple[str, ...]


def _level(levels: Mapping[str, int], joint: str) -> int | None:
    if joint in levels:
        return levels[joint]
    wanted = _key(joint)
    return next((level for name, level in levels.items() if _key(name) == wanted), None)


def matches(
    condition: Condition,
    landmark_type: int,
    levels: Mapping[str, int],
    finding: tuple[str, str] | None = None,
) -> bool:
    """Alg. 8: does ``condition`` hold for a landmark of this type with these joint levels?

    A joint missing from ``levels`` has no level (the thesis's *none*): ``@J$L`` is false for it.
    ``finding``: (kind, angle) when a finding of the recording is matched instead of a landmark
    (``%KIND$ANGLE`` holds for it alone); None for a landmark, where no ``%`` condition holds.
    """
    match condition:
        case FindingIs(kind=kind, angle=angle):
            return finding == (kind, angle)
        case LandmarkType(type=number):
            return number == landmark_type
        case JointLevel(joint=joint, level=level):
            return _level(levels, joint) == level
        case Not(operand=operand):
            return not matches(operand, landmark_type, levels, finding)
        case And(left=left, right=right):
            return matches(left, landmark_type, levels, finding) and matches(
                right, landmark_type, levels, finding
            )
        case Or(left=left, right=right):
            return matches(left, landmark_type, levels, finding) or matches(
                right, landmark_type, levels, finding
            )
    raise TypeError(f"not a condition: {condition!r}")


def _leaves(condition: Condition) -> Iterator[LandmarkType | JointLevel | FindingIs]:
    match condition:
        case Not(operand=operand):
            yield from _leaves(operand)
        case And(left=left, right=right) | Or(left=left, right=right):
            yield from _leaves(left)
            yield from _leaves(right)
        case LandmarkType() | JointLevel() | FindingIs():
            yield condition


@dataclass(frozen=True)
class Grammar:
    """A parsed assessment grammar (the thesis's *assessment tree*): its rules in source order."""

    rules: tuple[Rule, ...]

    @classmethod
    def parse(cls, text: str) -> Grammar:
        """Parse grammar text; raises :class:`GrammarError` with line and column when malformed."""
        return cls(parse_rules(text))

    def to_text(self) -> str:
        """Grammar text that parses back to an equal grammar (one rule per line)."""
        return "".join(format_rule(rule) + "\n" for rule in self.rules)

    @property
    def joints(self) -> frozenset[str]:
        """Joint names the rules mention, as written."""
        return frozenset(
            n.joint for r in self.rules for n in _leaves(r.condition) if isinstance(n, JointLevel)
        )

    @property
    def types(self) -> frozenset[int]:
        """Landmark types the rules mention."""
        return frozenset(
            n.type for r in self.rules for n in _leaves(r.condition) if isinstance(n, LandmarkType)
        )

    @property
    def has_findings(self) -> bool:
        """Whether any rule speaks of a finding (``%KIND$ANGLE``): the corrections style."""
        return any(isinstance(n, FindingIs) for r in self.rules for n in _leaves(r.condition))

    def match(
        self,
        landmark_type: int,
        levels: Mapping[str, int],
        finding: tuple[str, str] | None = None,
    ) -> Match:
        """Alg. 9: feedbacks and tips of every rule whose condition holds for this landmark (or,
        given ``finding`` = (kind, angle), for that finding of the recording)."""
        feedbacks: dict[str, None] = {}  # dicts keep grammar order and drop repeats
        tips: dict[str, None] = {}
        for rule in self.rules:
            if matches(rule.condition, landmark_type, levels, finding):
                if rule.feedback is not None:
                    feedbacks[rule.feedback] = None
                if rule.tip is not None:
                    tips[rule.tip] = None
        return Match(tuple(feedbacks), tuple(tips))

    def comments(
        self,
        assessments: Sequence[LandmarkAssessment],
        options: FeedbackOptions | None = None,
        choose: Chooser | None = None,
    ) -> list[Comment]:
        """Alg. 10 without the replay: one comment per landmark that has something to say.

        Landmarks are taken in frame order; a feedback said at an earlier landmark is introduced
        with "again"/"once more"; each tip is said only the first time it matches in the session.
        ``choose`` overrides how connectives are picked (default: seeded, see FeedbackOptions).
        """
        options = options or FeedbackOptions()
        choose = choose or VariedChooser(options.seed)
        said: set[str] = set()
        told: set[str] = set()
        result = []
        for landmark in sorted(assessments, key=lambda a: a.frame):
            found = self.match(landmark.type, landmark.levels)
            tips = [t for t in found.tips if t not in told]
            if not found.feedbacks and not tips:
                continue
            repeated = [f in said for f in found.feedbacks]
            feedback = compose_feedback(found.feedbacks, repeated, options, choose)
            tip = compose_tips(tips, options, choose)
            text = f"{feedback} {tip}".strip()
            result.append(Comment(landmark.frame, text, tip=tip, feedback=feedback))
            said.update(found.feedbacks)
            told.update(tips)
        return result

    def problems(
        self, joints: Collection[str], types: Collection[int] | None = None, n_levels: int = 4
    ) -> tuple[str, ...]:
        """Why rules may never fire for an exercise: unknown joints or types, levels out of range.

        For an admin form: the grammar parses, but these rules refer to things the exercise lacks.
        """
        known = {_key(j) for j in joints} | set(joints)
        found: dict[str, None] = {}  # keeps order, drops repeats
        for rule in self.rules:
            for node in _leaves(rule.condition):
                problem = _problem(node, known, types, n_levels)
                if problem:
                    found[f"line {rule.line}: {problem}"] = None
        return tuple(found)


def _problem(
    node: LandmarkType | JointLevel | FindingIs,
    known: set[str],
    types: Collection[int] | None,
    n_levels: int,
) -> str:
    if isinstance(node, FindingIs):
        known_kinds = ", ".join(KINDS)
        return "" if node.kind in KINDS else f"unknown finding {node.kind} ({known_kinds})"
    if isinstance(node, LandmarkType):
        unknown = types is not None and node.type not in types
        return f"the exercise has no landmark type {node.type}" if unknown else ""
    if node.joint not in known and _key(node.joint) not in known:
        return f"the exercise has no joint {node.joint}"
    if not 1 <= node.level <= n_levels:
        return f"level {node.level} of {node.joint} is outside 1..{n_levels}"
    return ""
