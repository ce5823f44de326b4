"""The HIERARCHY block of a BVH file: joints, offsets, channels and End Sites.

The parser walks a token stream with an explicit stack, so a deeply nested (or maliciously deep)
hierarchy ends in a clear `BVHError` instead of a recursion error.

Four quirks that common readers (Blender, bvhio, PyMO) accept are read with a warning in
`Hierarchy.warnings` instead of an error: a first joint declared with ``JOINT`` instead of
``ROOT``; words after ``End Site`` on its line (``End Site LeftToe_End``); digits glued to it
(``End Site4``, read as ``End Site``; any other word there is still an error); and a line inside a
joint that starts with an unknown keyword (``JOINTTYPE ball``, ``ROTATIONORDER ZXY``), which is
skipped.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from analysis.bvh.errors import BVHError

CHANNEL_NAMES = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")
_CANONICAL = {name.lower(): name for name in CHANNEL_NAMES}
MAX_JOINTS = 1024
MAX_DEPTH = 256
_COUNTS = frozenset("0123456")
_KEYWORD = re.compile(r"[A-Za-z_][A-Za-z0-9_.:-]*")
_NUMBERED_SITE = re.compile(r"Site[0-9]+")


@dataclass
class JointDraft:
    """A joint while the hierarchy is being read (turned into arrays once complete)."""

    name: str
    parent: int
    line: int
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    channels: tuple[str, ...] = ()
    has_offset: bool = False
    has_channels: bool = False


@dataclass
class Hierarchy:
    joints: list[JointDraft] = field(default_factory=list)
    end_parents: list[int] = field(default_factory=list)
    end_offsets: list[tuple[float, float, float]] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


class TokenStream:
    """Tokens of the header with their 1-based line numbers."""

    def __init__(self, lines: list[str], first_line: int) -> None:
        # str.split() splits on the same whitespace as the regex \S+, four times faster.
        self.tokens: list[tuple[str, int]] = [
            (token, first_line + i) for i, line in enumerate(lines) for token in line.split()
        ]
        self.pos = 0
        self.last_line = first_line + max(len(lines) - 1, 0)

    def peek(self) -> tuple[str, int] | None:
        return self.tokens[self.pos] if self.pos < len(self.tokens) else None

    def next(self, what: str) -> tuple[str, int]:
        token = self.peek()
        if token is None:
            raise BVHError(f"the hierarchy ends early: expected {what}", self.last_line)
        self.pos += 1
        return token

    def expect(self, literal: str) -> int:
        token, line = self.next(f"'{literal}'")
        if token != literal:
            raise BVHError(f"expected '{literal}' but found '{token}'", line)
        return line

    def starts_line(self) -> bool:
        """Whether the token just read (at pos - 1) is the first on its line."""
        return self.pos < 2 or self.tokens[self.pos - 2][1] != self.tokens[self.pos - 1][1]

    def rest_of_line(self, line: int) -> list[str]:
        words = []
        while (token := self.peek()) is not None and token[1] == line and token[0] != "{":
            words.append(token[0])
            self.pos += 1
        return words


def parse_float(token: str, line: int, what: str) -> float:
    try:
        value = float(token)
    except ValueError:
        raise BVHError(f"{what} '{token}' is not a number", line) from None
    if not math.isfinite(value):
        raise BVHError(f"{what} is not finite ({token})", line)
    return value


def read_offset(stream: TokenStream) -> tuple[float, float, float]:
    _, line = stream.next("OFFSET values")
    values = tuple(parse_float(stream.next("an OFFSET value")[0], line, "OFFSET") for _ in range(3))
    return values  # type: ignore[return-value]


def read_channels(stream: TokenStream, line: int) -> tuple[str, ...]:
    count_token, _ = stream.next("the channel count")
    if count_token not in _COUNTS:
        raise BVHError(f"CHANNELS count must be 0 to 6, found '{count_token[:40]}'", line)
    names = []
    for _ in range(int(count_token)):
        token, token_line = stream.next("a channel name")
        canonical = _CANONICAL.get(token.lower())
        if canonical is None:
            raise BVHError(f"unknown channel '{token}'", token_line)
        if canonical in names:
            raise BVHError(f"channel '{token}' is declared twice", token_line)
        names.append(canonical)
    return tuple(names)


def read_joint_body(stream: TokenStream, joint: JointDraft, keyword: str, line: int) -> None:
    if keyword == "OFFSET":
        stream.pos -= 1
        joint.offset, joint.has_offset = read_offset(stream), True
    elif keyword == "CHANNELS":
        joint.channels, joint.has_channels = read_channels(stream, line), True


def open_joint(stream: TokenStream, tree: Hierarchy, parent: int, line: int) -> int:
    words = stream.rest_of_line(line)
    if not words:
        raise BVHError("a joint needs a name", line)
    if len(tree.joints) >= MAX_JOINTS:
        raise BVHError(f"more than {MAX_JOINTS} joints", line)
    tree.joints.append(JointDraft(" ".join(words), parent, line))
    stream.expect("{")
    return len(tree.joints) - 1


def read_end_site(stream: TokenStream, tree: Hierarchy, parent: int, line: int) -> None:
    site, _ = stream.next("'Site'")
    if _NUMBERED_SITE.fullmatch(site):
        # 'End Site4': an exporter numbering its End Sites; the number names nothing.
        tree.warnings.append(f"line {line}: read 'End {site[:40]}' as 'End Site'")
    elif site != "Site":
        raise BVHError(f"expected 'End Site' but found 'End {site}'", line)
    stray = stream.rest_of_line(line)
    if stray:
        shown = " ".join(stray)[:40]
        tree.warnings.append(f"line {line}: ignored '{shown}' after 'End Site'")
    stream.expect("{")
    keyword, key_line = stream.next("OFFSET")
    if keyword != "OFFSET":
        raise BVHError(f"an End Site needs an OFFSET, found '{keyword}'", key_line)
    stream.pos -= 1
    tree.end_parents.append(parent)
    tree.end_offsets.append(read_offset(stream))
    stream.expect("}")


def check_joint_complete(joint: JointDraft, line: int) -> None:
    if not joint.has_offset:
        raise BVHError(f"joint '{joint.name}' has no OFFSET", line)
    if not joint.has_channels:
        raise BVHError(f"joint '{joint.name}' has no CHANNELS", line)


def next_in_joint(stream: TokenStream, joint: JointDraft) -> tuple[str, int]:
    if stream.peek() is None:
        raise BVHError(
            f"unbalanced braces: joint '{joint.name}' (line {joint.line}) is never closed",
            stream.last_line,
        )
    return stream.next("'}'")


def parse_hierarchy(lines: list[str], first_line: int) -> Hierarchy:
    """Parse the lines between HIERARCHY and MOTION (exclusive) into joints and End Sites."""
    stream = TokenStream(lines, first_line)
    tree = Hierarchy()
    token, line = stream.next("ROOT")
    if token == "JOINT":
        tree.warnings.append(f"line {line}: the skeleton starts with JOINT instead of ROOT")
    elif token != "ROOT":
        raise BVHError(f"expected ROOT but found '{token}'", line)
    stack = [open_joint(stream, tree, -1, line)]
    while stack:
        joint = tree.joints[stack[-1]]
        keyword, line = next_in_joint(stream, joint)
        if keyword in ("OFFSET", "CHANNELS"):
            read_joint_body(stream, joint, keyword, line)
        elif keyword == "JOINT":
            if len(stack) >= MAX_DEPTH:
                raise BVHError(f"joints nested deeper than {MAX_DEPTH} levels", line)
            stack.append(open_joint(stream, tree, stack[-1], line))
        elif keyword == "End":
            read_end_site(stream, tree, stack[-1], line)
        elif keyword == "}":
            check_joint_complete(joint, line)
            stack.pop()
        else:
            other_in_joint(stream, tree, joint, keyword, line)
    check_single_root(stream)
    return tree


def other_in_joint(
    stream: TokenStream, tree: Hierarchy, joint: JointDraft, keyword: str, line: int
) -> None:
    """A token inside a joint that is not OFFSET, CHANNELS, JOINT, End or '}'."""
    if keyword == "ROOT":
        raise BVHError("a ROOT inside another joint (unbalanced braces?)", line)
    if _KEYWORD.fullmatch(keyword) and stream.starts_line():
        skip_unknown_line(stream, tree, joint, keyword, line)
        return
    raise BVHError(f"unexpected '{keyword}' in joint '{joint.name}'", line)


def skip_unknown_line(
    stream: TokenStream, tree: Hierarchy, joint: JointDraft, keyword: str, line: int
) -> None:
    """Skip a line inside a joint that starts with a keyword BVH does not define."""
    words = " ".join([keyword, *stream.rest_of_line(line)])[:40]
    tree.warnings.append(f"line {line}: ignored the unknown line '{words}' in joint '{joint.name}'")


def check_single_root(stream: TokenStream) -> None:
    token = stream.peek()
    if token is None:
        return
    if token[0] == "ROOT":
        raise BVHError("several ROOTs: only one skeleton per file is supported", token[1])
    if token[0] == "}":
        raise BVHError("unbalanced braces: one '}' too many", token[1])
    raise BVHError(f"unexpected '{token[0]}' after the skeleton", token[1])
