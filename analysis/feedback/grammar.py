"""The assessment meta-grammar of thesis 004 (§7.2.4, Listing 7.2): parser, syntax tree, printer.

An assessment grammar is a list of rules, one per line in practice (newlines are only whitespace,
so a long condition may wrap), e.g.::

    type$2 & @LEFT_KNEE$3 -> F:"Your left knee needs to be bent much more"
    type$2 & (@LEFT_KNEE$2 | @LEFT_KNEE$3) -> T:"Try ducking lower"

* ``type$N`` holds when the landmark is of type N; ``@JOINT$L`` when JOINT was assessed at level L.
* ``!`` (not) binds tightest, then ``&`` (and), then ``|`` (or); parentheses group.
  Listing 7.2 gives ``&`` and ``|`` one LOGICAL production without a precedence; every grammar of
  Appendix E parenthesises mixed ``&``/``|``, so the usual precedence changes none of them.
* After ``->`` come a feedback ``F:"…"``, a tip ``T:"…"``, or both separated by a comma, either
  order.
  Listing 7.2 prints the arrow as ``=``; every listing of the thesis writes ``->``, which we follow.
* Texts are in double quotes on one line, with no escapes (Listing 7.2's STRING has no quote).
* Extension: ``#`` starts a comment that runs to the end of the line.
* Extension (corrections, issue 17): ``%KIND$ANGLE`` holds for a finding of the recording (see
  `analysis.assessment.findings`): KIND is less, more, extra, good, fast or slow, ANGLE a clinical
  angle (``%less$knee_flexion_left``); ``%fast`` / ``%slow`` have no angle. Their texts may hold
  ``{part}``, ``{amount}``, ``{patient}``, ``{tutor}``, ``{percent}`` and ``{repetitions}``, filled
  with the finding's figures (`analysis.feedback.advice`).

:func:`parse_rules` raises :class:`GrammarError` (line, column, plain-words message) on bad input.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache, reduce
from typing import Any

from lark import Lark, Token, Transformer, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken
from lark.tree import Meta

_META_GRAMMAR = r"""
start: rule*
rule: condition _ARROW predicate
predicate: feedback (_COMMA tip)?   -> feedback_first
         | tip (_COMMA feedback)?   -> tip_first
feedback: _FEEDBACK TEXT
tip: _TIP TEXT
?condition: and_expr (_OR and_expr)*
?and_expr: not_expr (_AND not_expr)*
?not_expr: _NOT not_expr -> negation
         | atom
?atom: _LPAR condition _RPAR
     | _TYPE _DOLLAR NUMBER       -> landmark_type
     | _AT JOINT _DOLLAR NUMBER   -> joint_level
     | _PCT JOINT (_DOLLAR JOINT)? -> finding_is

_ARROW: "->"
_COMMA: ","
_FEEDBACK: "F:"
_TIP: "T:"
_OR: "|"
_AND: "&"
_NOT: "!"
_LPAR: "("
_RPAR: ")"
_TYPE: "type"
_DOLLAR: "$"
_AT: "@"
_PCT: "%"
JOINT: /[A-Za-z_][A-Za-z0-9_.:]*/
NUMBER: /[0-9]+/
TEXT: /"[^"\n]*"/
COMMENT: /#[^\n]*/
%ignore COMMENT
%ignore /[ \t\f\r\n]+/
"""

# What a therapist-admin reads instead of lark's terminal names.
_TERMINAL_WORDS = {
    "_ARROW": "'->'",
    "_COMMA": "','",
    "_FEEDBACK": 'F:"…"',
    "_TIP": 'T:"…"',
    "_OR": "'|'",
    "_AND": "'&'",
    "_NOT": "'!'",
    "_LPAR": "'('",
    "_RPAR": "')'",
    "_TYPE": "type$N",
    "_DOLLAR": "'$'",
    "_AT": "@body_part$N",
    "_PCT": "%KIND$ANGLE",
    "JOINT": "a body part",
    "NUMBER": "a number",
    "TEXT": "a text in double quotes",
    "$END": "the end of the grammar",
}


class GrammarError(ValueError):
    """An assessment grammar that cannot be parsed; ``line``/``column`` are 1-based."""

    def __init__(self, message: str, line: int, column: int, source_line: str = "") -> None:
        super().__init__(f"line {line}, column {column}: {message}")
        self.message = message
        self.line = line
        self.column = column
        self.source_line = source_line

    @property
    def context(self) -> str:
        """The offending line with a caret under the column (for display in a monospace font)."""
        return f"{self.source_line}\n{' ' * (self.column - 1)}^"


@dataclass(frozen=True)
class LandmarkType:
    """``type$N``: the landmark is of type ``type``."""

    type: int


@dataclass(frozen=True)
class JointLevel:
    """``@JOINT$L``: ``joint`` was assessed at ``level`` (1 = as the tutor … N_A = worst)."""

    joint: str
    level: int


@dataclass(frozen=True)
class FindingIs:
    """``%KIND$ANGLE``: the recording has a finding of this kind on this angle ("" for tempo)."""

    kind: str
    angle: str = ""


@dataclass(frozen=True)
class Not:
    operand: Condition


@dataclass(frozen=True)
class And:
    left: Condition
    right: Condition


@dataclass(frozen=True)
class Or:
    left: Condition
    right: Condition


Condition = LandmarkType | JointLevel | FindingIs | Not | And | Or


@dataclass(frozen=True)
class Rule:
    """One line of the grammar: when ``condition`` holds, say ``feedback`` and/or ``tip``.

    ``line`` is where the rule starts in the source text (0 when built in code); it is not part of
    equality so that a printed and re-parsed grammar compares equal.
    """

    condition: Condition
    feedback: str | None = None
    tip: str | None = None
    line: int = field(default=0, compare=False)

    def __post_init__(self) -> None:
        if self.feedback is None and self.tip is None:
            raise ValueError("a rule needs a feedback, a tip or both")


class _ToTree(Transformer[Token, object]):
    """Turns lark's parse tree into the frozen syntax tree."""

    def start(self, rules: list[Rule]) -> tuple[Rule, ...]:
        return tuple(rules)

    @v_args(meta=True)
    def rule(self, meta: Meta, children: list[Any]) -> Rule:
        condition, (feedback, tip) = children
        return Rule(condition, feedback, tip, line=getattr(meta, "line", 0))

    def feedback_first(self, children: list[str]) -> tuple[str | None, str | None]:
        return children[0], children[1] if len(children) > 1 else None

    def tip_first(self, children: list[str]) -> tuple[str | None, str | None]:
        return (children[1] if len(children) > 1 else None), children[0]

    def feedback(self, children: list[Token]) -> str:
        return str(children[0])[1:-1]

    tip = feedback

    def condition(self, children: list[Condition]) -> Condition:
        return reduce(Or, children)

    def and_expr(self, children: list[Condition]) -> Condition:
        return reduce(And, children)

    def negation(self, children: list[Condition]) -> Condition:
        return Not(children[0])

    def landmark_type(self, children: list[Token]) -> Condition:
        return LandmarkType(int(children[0]))

    def joint_level(self, children: list[Token]) -> Condition:
        return JointLevel(str(children[0]), int(children[1]))

    def finding_is(self, children: list[Token]) -> Condition:
        return FindingIs(str(children[0]), str(children[1]) if len(children) > 1 else "")


@cache
def _parser() -> Lark:
    return Lark(
        _META_GRAMMAR,
        parser="lalr",
        lexer="contextual",
        propagate_positions=True,
        maybe_placeholders=False,
    )


def parse_rules(text: str) -> tuple[Rule, ...]:
    """Parse an assessment grammar into its rules, in source order (the order of Alg. 9)."""
    try:
        tree = _parser().parse(text)
    except UnexpectedInput as error:
        raise _explain(error, text) from None
    return _ToTree().transform(tree)  # type: ignore[return-value]


# A joint condition, or what the rename skips: a quoted text or a comment (which may hold "@x$1").
_JOINT_OR_SKIPPED = re.compile(r'"[^"\n]*"|#[^\n]*|(@\s*)([A-Za-z_][A-Za-z0-9_.:]*)')


def rename_joints(text: str, rename: Callable[[str], str]) -> str:
    """``text`` with each body part written in an ``@JOINT$L`` condition replaced by
    ``rename(JOINT)``, everything else (texts, comments, layout, so line numbers) kept as is.

    The exercise page lets a therapist write body parts in the words of its ticks (``@hips$3``);
    the analysis matches a grammar's joints to the rig's own names (``Waist``)."""

    def replaced(found: re.Match[str]) -> str:
        if found.group(2) is None:
            return found.group(0)
        return found.group(1) + rename(found.group(2))

    return _JOINT_OR_SKIPPED.sub(replaced, text)


def _line_of(text: str, line: int) -> str:
    lines = text.splitlines()
    return lines[line - 1] if 0 < line <= len(lines) else ""


def _end_position(text: str) -> tuple[int, int]:
    """Just after the last visible character: where the missing part should have been."""
    shown = text.rstrip()
    return shown.count("\n") + 1, len(shown) - (shown.rfind("\n") + 1) + 1


def _explain(error: UnexpectedInput, text: str) -> GrammarError:
    """Turn lark's exception into a message about the grammar's own vocabulary."""
    if isinstance(error, UnexpectedCharacters):
        line, column = error.line, error.column
        message = _explain_character(error.char)
    elif isinstance(error, UnexpectedToken) and error.token.type == "$END":
        line, column = _end_position(text)
        message = f"the grammar ends in the middle of a rule; expected {_expected(error)}"
    elif isinstance(error, UnexpectedToken):
        line, column = error.token.line or 1, error.token.column or 1
        message = _explain_token(error, text)
    else:  # pragma: no cover - LALR raises only the two kinds above
        line, column, message = error.line, error.column, str(error)
    return GrammarError(message, line, column, _line_of(text, line))


def _explain_character(char: str) -> str:
    if char == '"':
        return 'this text in quotes is not closed: add the closing " on the same line'
    if char in "=->":
        return "write the arrow between the condition and its feedback or tip as '->'"
    return (
        f"unexpected character {char!r}; a rule looks like "
        'type$2 & @left_knee$3 -> F:"feedback", T:"tip"'
    )


def _expected(error: UnexpectedToken) -> str:
    words = sorted({_TERMINAL_WORDS.get(name, name) for name in error.expected})
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " or " + words[-1]


def _explain_token(error: UnexpectedToken, text: str) -> str:
    token, expected = error.token, set(error.expected)
    found = f"{token.value!r}" if token.type != "TEXT" else "a text in quotes"
    # LALR merges look-ahead sets, so ')' may be "expected" outside parentheses: count them.
    opened = _unclosed_parenthesis(text, token.start_pos or 0)
    if opened and "_RPAR" in expected:
        line, column = opened
        return f"missing ')' to close the '(' at line {line}, column {column}; found {found}"
    if token.type == "_RPAR":
        return "this ')' has no matching '('"
    if "_ARROW" in expected:
        return f"missing '->' between the condition and its feedback or tip; found {found}"
    return _explain_misplaced(error, found)


def _explain_misplaced(error: UnexpectedToken, found: str) -> str:
    kind = error.token.type
    if kind == "JOINT" and {"_AT", "_TYPE"} & set(error.expected):
        return (
            f"unknown word {found}: write type$N for a kind of key pose or @body_part$N for a "
            "body part"
        )
    if kind in {"_FEEDBACK", "_TIP"} and "_COMMA" in error.expected:
        return "separate the feedback and the tip with ','; a rule has at most one of each"
    if kind == "TEXT":
        return f"a text in quotes must follow F: or T:; expected {_expected(error)}"
    return f"found {found} where {_expected(error)} was expected"


_SKIPPED = re.compile(r'"[^"\n]*"?|#[^\n]*')


def _unclosed_parenthesis(text: str, before: int) -> tuple[int, int] | None:
    """Line and column of the last '(' still open at offset ``before`` (quotes/comments skipped)."""
    visible = _SKIPPED.sub(lambda m: " " * len(m.group()), text[:before])
    opened: list[int] = []
    for offset, char in enumerate(visible):
        if char == "(":
            opened.append(offset)
        elif char == ")" and opened:
            opened.pop()
    if not opened:
        return None
    offset = opened[-1]
    return text.count("\n", 0, offset) + 1, offset - (text.rfind("\n", 0, offset) + 1) + 1


# Printing: the inverse of parsing, used to write generated grammars.

_PRECEDENCE = {Or: 1, And: 2, Not: 3, LandmarkType: 4, JointLevel: 4, FindingIs: 4}
_JOINT = re.compile(r"[A-Za-z_][A-Za-z0-9_.:]*\Z")


def format_condition(condition: Condition, parent: int = 0) -> str:
    """Condition as grammar text, with parentheses only where precedence needs them."""
    match condition:
        case LandmarkType(type=number):
            return f"type${number}"
        case JointLevel(joint=joint, level=level):
            if not _JOINT.match(joint):
                raise ValueError(f"joint name {joint!r} cannot be written in a grammar")
            return f"@{joint}${level}"
        case FindingIs(kind=kind, angle=angle):
            if not _JOINT.match(kind) or (angle and not _JOINT.match(angle)):
                raise ValueError(f"finding {kind!r} {angle!r} cannot be written in a grammar")
            return f"%{kind}${angle}" if angle else f"%{kind}"
        case Not(operand=operand):
            return "!" + format_condition(operand, _PRECEDENCE[Not])
        case And(left=left, right=right) | Or(left=left, right=right):
            own = _PRECEDENCE[type(condition)]
            symbol = " & " if isinstance(condition, And) else " | "
            # Right operands get own + 1: the parser folds to the left, so a | (b | c) keeps its
            # parentheses and prints back to the same tree.
            body = format_condition(left, own) + symbol + format_condition(right, own + 1)
            return f"({body})" if own < parent else body
    raise TypeError(f"not a condition: {condition!r}")


def _quoted(text: str) -> str:
    if '"' in text or "\n" in text:
        raise ValueError(f"texts in a grammar cannot hold a double quote or a newline: {text!r}")
    return f'"{text}"'


def format_rule(rule: Rule) -> str:
    """One rule as one line of grammar text."""
    said = [f"F:{_quoted(rule.feedback)}"] if rule.feedback is not None else []
    said += [f"T:{_quoted(rule.tip)}"] if rule.tip is not None else []
    return f"{format_condition(rule.condition)} -> {', '.join(said)}"
