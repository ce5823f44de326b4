"""Words for the feedback of thesis 004 (§7.2.4, §7.4.2): sentences, joint names, default grammars.

The thesis's generated feedback (Figures 7.8, 7.9, D.2–D.4) strings the matched feedback texts of
one landmark into sentences with varied connectives, then adds the tips not said before::

    "On this occasion, your left knee needs to be bent a little bit more. And your right knee needs
     to be bent a little bit more. Try ducking lower."
    "This time, once more, your left knee needs to be bent a little bit more. Again, your right knee
     needs to be bent a little bit more."

* the first sentence opens with "On this occasion," / "This time," / "Now,";
* a feedback already said earlier in the session gets "again" / "once more";
* the other new feedbacks and the second and later tips get "Furthermore," / "In addition," /
  "Additionally," / "And".

The thesis picks the words at random; we pick them with a seeded generator that avoids repeating the
previous choice of the same kind, so a session reads varied and is reproducible.
"""

from __future__ import annotations

import random
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

from analysis.clinical.labels import (
    ANGLE_PARTS,
    ANGLE_PAST,
    INSTRUCTIONS,
    STILL_INSTRUCTION,
    angle_part,
    split_side,
)
from analysis.feedback.grammar import (
    And,
    Condition,
    FindingIs,
    JointLevel,
    LandmarkType,
    Or,
    Rule,
    format_rule,
)

# kind of phrase ("opener", "repeat", "addition") and the words allowed -> the words chosen
Chooser = Callable[[str, Sequence[str]], str]


@dataclass(frozen=True)
class FeedbackOptions:
    """Connectives of the sentences (each with its punctuation) and the seed that picks them."""

    seed: int = 0
    openers: tuple[str, ...] = ("On this occasion,", "This time,", "Now,")
    repeats: tuple[str, ...] = ("Again,", "Once more,")
    additions: tuple[str, ...] = ("Furthermore,", "In addition,", "Additionally,", "And")

    def __post_init__(self) -> None:
        if not (self.openers and self.repeats and self.additions):
            raise ValueError("openers, repeats and additions each need at least one phrase")


class VariedChooser:
    """Seeded random choice of connectives that avoids the obvious repetitions.

    Within one comment a kind never gets the same phrase twice in a row ("Again, … Again, …"), and
    consecutive comments open differently. Memory of the other kinds is dropped when a comment
    opens, otherwise a kind with two phrases would alternate in lockstep over the whole session.
    """

    def __init__(self, seed: int) -> None:
        self._random = random.Random(seed)
        self._last: dict[str, str] = {}

    def __call__(self, kind: str, phrases: Sequence[str]) -> str:
        if kind == "opener":
            self._last = {kind: self._last[kind]} if kind in self._last else {}
        fresh = [p for p in phrases if p != self._last.get(kind)] or list(phrases)
        choice = self._random.choice(fresh)
        self._last[kind] = choice
        return choice


def lower_first(text: str) -> str:
    """'Your left arm …' -> 'your left arm …' to follow a connective; keeps 'I' and acronyms."""
    word = text.split(" ", 1)[0]
    if not word or word == "I" or (len(word) > 1 and word.isupper()):
        return text
    return text[0].lower() + text[1:]


def _sentence(*parts: str) -> str:
    text = " ".join(p for p in parts if p)
    return text if text.endswith((".", "!", "?")) else text + "."


def compose_feedback(
    feedbacks: Sequence[str], repeated: Sequence[bool], options: FeedbackOptions, choose: Chooser
) -> str:
    """Sentences for one landmark's feedback texts, in grammar order.

    ``repeated[i]`` says whether ``feedbacks[i]`` was already said earlier in the session.
    """
    sentences = []
    for index, (text, again) in enumerate(zip(feedbacks, repeated, strict=True)):
        if index == 0:
            opener = choose("opener", options.openers)
            repeat = lower_first(choose("repeat", options.repeats)) if again else ""
            sentences.append(_sentence(opener, repeat, lower_first(text)))
        else:
            kind, phrases = (
                ("repeat", options.repeats) if again else ("addition", options.additions)
            )
            sentences.append(_sentence(choose(kind, phrases), lower_first(text)))
    return " ".join(sentences)


def compose_tips(tips: Sequence[str], options: FeedbackOptions, choose: Chooser) -> str:
    """Sentences for the new tips of one landmark: the first as written, the next ones joined."""
    sentences = [_sentence(tips[0])] if tips else []
    sentences += [
        _sentence(choose("addition", options.additions), lower_first(t)) for t in tips[1:]
    ]
    return " ".join(sentences)


# Joint names -----------------------------------------------------------------------------------

_WORD = re.compile(r"[A-Z]+(?=[A-Z][a-z])|[A-Z]?[a-z]+|[A-Z]+|[0-9]+")
_SIDES = {"left": "left", "l": "left", "right": "right", "r": "right"}
# Skeleton vocabularies (UI-PRMD, CMU, Mixamo) name bones in ways a patient would not say.
_PLAIN_WORDS = {
    "up leg": "thigh",
    "upper leg": "thigh",
    "fore arm": "forearm",
    "collar": "collarbone",
    "toe base": "toes",
    "head tip": "top of the head",
    "head end": "top of the head",
}
_PLAIN = re.compile(r"\b(" + "|".join(map(re.escape, _PLAIN_WORDS)) + r")\b")


def joint_label(name: str) -> str:
    """Human-readable joint name: 'LeftKnee', 'KneeLeft', 'LEFT_KNEE', 'l_knee' -> 'left knee'.

    Namespaces ('mixamorig:LeftArm') are dropped and bone words made plain ('LeftUpperLeg' ->
    'left thigh', 'LeftCollar' -> 'left collarbone'). Also the key under which grammar joints
    and assessed joints are matched, so 'LEFT_KNEE' in a grammar matches 'LeftKnee' in a skeleton.
    """
    words = [w.lower() for w in _WORD.findall(re.split(r"[:|]", name)[-1])]
    side = ""
    if len(words) > 1 and words[0] in _SIDES:
        side = _SIDES[words.pop(0)]
    elif len(words) > 1 and words[-1] in _SIDES:
        side = _SIDES[words.pop()]
    body = _PLAIN.sub(lambda m: _PLAIN_WORDS[m.group(1)], " ".join(words))
    if not body:
        return name.strip().lower()
    return f"{side} {body}" if side else body


# Default grammar -----------------------------------------------------------------------------

_LEVEL_WORDS = {2: "slightly differently", 3: "noticeably differently", 4: "very differently"}
_GRAMMAR_JOINT = re.compile(r"[^A-Za-z0-9_.:]")


def _moment(type_name: str, number: int) -> str:
    name = lower_first(type_name.strip())
    if not name:
        return f"at key pose {number}"
    return f"at {name}" if name.startswith("the ") else f"at the {name}"


def _grammar_joint(name: str) -> str:
    """A joint name the grammar can hold that still matches ``name`` (see :func:`joint_label`)."""
    written = _GRAMMAR_JOINT.sub("_", name)
    if not written[:1].isalpha() and written[:1] != "_":
        written = "_" + written
    if joint_label(written) != joint_label(name):
        raise ValueError(f"joint name {name!r} cannot be written in a grammar")
    return written


def _joint_rules(joint: str, number: int, moment: str, levels: Sequence[int]) -> list[Rule]:
    label, written = joint_label(joint), _grammar_joint(joint)
    rules = []
    for level in levels:
        how = _LEVEL_WORDS.get(level, "differently")
        feedback = f"{moment}, your {label} moved {how} from the demonstration"
        condition = And(LandmarkType(number), JointLevel(written, level))
        rules.append(Rule(condition, feedback=feedback[0].upper() + feedback[1:]))
    anyone: Condition = JointLevel(written, levels[0])
    for level in levels[1:]:
        anyone = Or(anyone, JointLevel(written, level))
    tip = f"Look at the instructor's {label} {moment} and try to match it"
    rules.append(Rule(And(LandmarkType(number), anyone), tip=tip))
    return rules


# a trunk lean held all through (analysis.assessment.findings: "held" is forward / to the right)
HELD_INSTRUCTIONS = {
    ("trunk_flexion", "held"): "Straighten your {part}, by about {amount}: it leaned that much "
    "further forward than the demonstration's all through the movement",
    ("trunk_flexion", "held_back"): "Lean your {part} further forward, by about {amount}: it "
    "leaned that much further back than the demonstration's all through the movement",
    ("trunk_lateral_flexion", "held"): "Straighten your {part}, by about {amount}: it leaned that "
    "much further to the right than the demonstration's all through the movement",
    ("trunk_lateral_flexion", "held_back"): "Straighten your {part}, by about {amount}: it leaned "
    "that much further to the left than the demonstration's all through the movement",
}

# the compensations measured from positions (analysis.assessment.compensations)
COMPENSATION_INSTRUCTIONS = {
    ("trunk_rotation", "extra"): "Keep your trunk facing forward, by about {amount}: it turned "
    "through {patient} where the demonstration's turns through {tutor}",
    ("shoulder_hike", "extra"): "Keep your {part} down, by about {amount}: it rose through "
    "{patient} where the demonstration's rises through {tutor}",
    ("knee_valgus", "extra"): "Keep your {part} in line over your foot, by about {amount}: it "
    "moved inward and outward through {patient} where the demonstration's moves through {tutor}",
}
COMPENSATION_NAMES = ("trunk_rotation", *(f"{base}_{side}" for base in ("shoulder_hike",
                      "knee_valgus") for side in ("left", "right")))  # fmt: skip


def _finding_rule(kind: str, angle: str) -> Rule:
    """The default sentence of one finding (`analysis.feedback.advice` fills the fields)."""
    base = split_side(angle)[0]
    part, past = angle_part(angle), ANGLE_PAST.get(base, "moved")
    if (base, kind) in COMPENSATION_INSTRUCTIONS:
        text = COMPENSATION_INSTRUCTIONS[base, kind].replace("{part}", part)
        return Rule(FindingIs(kind, angle), feedback=text + ", in {repetitions}")
    if kind in ("held", "held_back"):
        text = HELD_INSTRUCTIONS.get((base, kind), "Straighten your {part}").replace("{part}", part)
        return Rule(FindingIs(kind, angle), feedback=text + ", in {repetitions}")
    if kind == "extra":
        text = (f"{STILL_INSTRUCTION[1].format(part=part)}: it {past} {{patient}} where the "
                "demonstration stays within {tutor}, in {repetitions}")  # fmt: skip
    elif kind == "good":
        text = (f"Your {part} {past} {{patient}}, as far as the demonstration's {{tutor}}, "
                "in {repetitions}")  # fmt: skip
    else:
        told = INSTRUCTIONS[(base, kind)][1].format(part=part)
        text = (f"{told}, by about {{amount}}: it {past} {{patient}} against the "
                "demonstration's {tutor} ({percent} of its range) in {repetitions}")  # fmt: skip
    return Rule(FindingIs(kind, angle), feedback=text)


_TEMPO_RULES = (
    Rule(FindingIs("fast"), feedback="Slow down the movement of your {part}, by about {amount}: "
         "each repetition took {percent} of the demonstration's time in {repetitions}"),
    Rule(FindingIs("slow"), feedback="Speed up the movement of your {part}, by about {amount}: "
         "each repetition took {percent} of the demonstration's time in {repetitions}"),
)  # fmt: skip


def correction_rules() -> list[Rule]:
    """The default ``%KIND$ANGLE`` rules: every clinical angle the body has, and the tempo."""
    # the names of analysis.clinical.ANGLE_NAMES, in the labels' order (the rules' order)
    ANGLE_NAMES = [
        name
        for base in ANGLE_PARTS
        for name in ((base,) if base.startswith("trunk") else (f"{base}_left", f"{base}_right"))
    ]
    rules = [
        _finding_rule(kind, angle) for angle in ANGLE_NAMES for kind in ("less", "more", "extra")
    ]
    rules += [_finding_rule(k, a) for a in ANGLE_NAMES if a.startswith("trunk")
              for k in ("held", "held_back")]  # fmt: skip
    rules += [_finding_rule("extra", name) for name in COMPENSATION_NAMES]
    rules += [_finding_rule("good", angle) for angle in ANGLE_NAMES]
    return rules + list(_TEMPO_RULES)


def default_grammar(
    joints: Sequence[str],
    landmark_types: Mapping[int, str] | Sequence[str],
    levels: Iterable[int] = (),
) -> str:
    """Grammar text for a new exercise, in the corrections style: per clinical angle, a sentence
    for a smaller range than the tutor's, a larger one, a movement where the tutor keeps still,
    and one for a good range; and the tempo (too fast, too slow). Example line::

        %less$knee_flexion_left -> F:"Bend your left knee more, by about {amount}: it bent
        {patient} against the demonstration's {tutor} ({percent} of its range) in {repetitions}"

    With ``levels`` (e.g. (3, 4)), the thesis's per-key-pose rules for each of ``joints`` at
    those levels follow (one comment per key pose: the older style, off by default).
    ``landmark_types`` maps type numbers to names, or lists the names of types 1, 2, ….
    """
    if not isinstance(landmark_types, Mapping):
        landmark_types = {n: name for n, name in enumerate(landmark_types, start=1)}
    if not joints:
        raise ValueError("a default grammar needs at least one joint")
    lines = [
        "# Default feedback grammar: edit the sentences freely. {part}, {amount}, {patient},",
        "# {tutor}, {percent} and {repetitions} are filled with the recording's figures.",
        "",
        *(format_rule(r) for r in correction_rules()),
    ]
    chosen = sorted(set(levels))
    for number, name in sorted(landmark_types.items()) if chosen else ():
        moment = _moment(name, number)
        for joint in joints:
            lines += ["", *(format_rule(r) for r in _joint_rules(joint, number, moment, chosen))]
    return "\n".join(lines) + "\n"
