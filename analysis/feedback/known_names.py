"""A grammar that parses may still speak of things the exercise lacks: ``@banana$3`` or ``type$9``
would never fire. `check_names` refuses such a grammar with a `GrammarError` at the first unknown
name, whose message lists the names the exercise knows (what the exercise form shows).

Body parts match as the feedback stage matches them (`analysis.feedback.sentences.matches`): by
the name as written or by its readable form (``LEFT_KNEE``, ``left_knee`` and ``LeftKnee`` are one
joint).
"""

from __future__ import annotations

import re
from collections.abc import Collection, Iterator, Mapping

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
    parse_rules,
)
from analysis.feedback.text import joint_label

Leaf = LandmarkType | JointLevel | FindingIs


def check_names(
    text: str,
    joints: Collection[str],
    types: Mapping[int, str] | Collection[int],
    also: Collection[str] = (),
) -> tuple[Rule, ...]:
    """Parse ``text`` and check every body part and key-pose type it names against the
    exercise's ``joints`` (as the grammar writes them) and ``types`` (numbers, or numbers with
    their names); returns the rules, raises `GrammarError` (line, column) otherwise. ``also``:
    body-part names accepted without being offered in the message (earlier spellings, which
    stored rules may still use)."""
    rules = parse_rules(text)
    known = {joint_label(j) for j in (*joints, *also)} | set(joints) | set(also)
    for rule in rules:
        for leaf in leaves(rule.condition):
            problem = unknown_name(leaf, known, joints, types)
            if problem:
                line, column = locate(text, rule.line, leaf)
                raise GrammarError(problem, line, column, _line(text, line))
    return rules


def leaves(condition: Condition) -> Iterator[Leaf]:
    match condition:
        case Not(operand=operand):
            yield from leaves(operand)
        case And(left=left, right=right) | Or(left=left, right=right):
            yield from leaves(left)
            yield from leaves(right)
        case _:
            yield condition


def unknown_name(
    leaf: Leaf,
    known: set[str],
    joints: Collection[str],
    types: Mapping[int, str] | Collection[int],
) -> str:
    """What is unknown about one condition, in plain words with the known names ("" if none)."""
    if isinstance(leaf, JointLevel):
        if leaf.joint in known or joint_label(leaf.joint) in known:
            return ""
        return f"this exercise has no body part '{leaf.joint}'; it knows {_listed(joints)}"
    if isinstance(leaf, LandmarkType):
        if leaf.type in types:
            return ""
        return f"this exercise has no key-pose type {leaf.type}; its types are {_types(types)}"
    if leaf.kind in KINDS:
        return ""
    return f"there is no finding '{leaf.kind}'; the findings are {', '.join(KINDS)}"


def _listed(names: Collection[str]) -> str:
    return ", ".join(sorted(names)) if names else "no body parts yet"


def _types(types: Mapping[int, str] | Collection[int]) -> str:
    if isinstance(types, Mapping):
        shown = [f"{t} ({types[t]})" if types[t] else str(t) for t in sorted(types)]
    else:
        shown = [str(t) for t in sorted(types)]
    return ", ".join(shown) if shown else "none yet"


def _pattern(leaf: Leaf) -> str:
    if isinstance(leaf, JointLevel):
        return rf"@\s*{re.escape(leaf.joint)}\b"
    if isinstance(leaf, LandmarkType):
        return rf"type\s*\$\s*0*{leaf.type}\b"
    return rf"%\s*{re.escape(leaf.kind)}\b"


def locate(text: str, first_line: int, leaf: Leaf) -> tuple[int, int]:
    """1-based (line, column) of ``leaf`` in the rule starting at ``first_line``."""
    lines = text.split("\n")
    pattern = re.compile(_pattern(leaf))
    for number in range(max(first_line, 1), len(lines) + 1):
        found = pattern.search(lines[number - 1].split("#", 1)[0])
        if found:
            return number, found.start() + 1
    return max(first_line, 1), 1


def _line(text: str, line: int) -> str:
    lines = text.split("\n")
    return lines[line - 1] if 0 < line <= len(lines) else ""
