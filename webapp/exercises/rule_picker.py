"""Feedback rules written by picking (body part, direction, degrees, sentence) instead of typing.

The picker writes a rule of the existing feedback language (`analysis.feedback.grammar`) and the
exercise's text is then checked as a typed one is (`annotate.grammar_verdict`), so experts keep
the text editor and both meet in the same stored text.

Two kinds of rule exist in that language, and the picker writes whichever the direction asks:

- "less" / "more": over the whole recording the body part's bending angle covered less (more) than
  the reference's (``%less$knee_flexion_left``); the analysis applies its own tolerance to these,
  so the degrees are not part of such a rule.
- "away": at a key pose the body part was at least N degrees away from the reference's pose. The
  assessment counts a body part's difference in levels, one level per `LEVEL_STEP_DEG` (its
  smallest step, `analysis.assessment.joints.ThresholdAssessor.floor_deg`), so N degrees is
  written as "level 1 + N // 10 or above" (``@left_knee$3 | @left_knee$4`` for 20°).
"""

from __future__ import annotations

from django import forms
from django.core.exceptions import ValidationError

from analysis.assessment.joints import N_LEVELS
from analysis.bvh import Skeleton
from analysis.bvh.rigs import identify
from webapp.exercises.annotate_data import type_names, written_names
from webapp.exercises.body_parts import offered, plain_labels

LEVEL_STEP_DEG = 10
# The body part named by the rig's structure -> the clinical angle that measures its bending.
ANGLE_OF_PART = {
    "upper_leg": "hip_flexion",
    "lower_leg": "knee_flexion",
    "foot": "ankle_dorsiflexion",
    "upper_arm": "shoulder_elevation",
    "forearm": "elbow_flexion",
    "chest": "trunk_flexion",
}
DIRECTIONS = (
    ("less", "bends less than in the reference (over each repetition)"),
    ("more", "bends more than in the reference (over each repetition)"),
    ("away", "is away from the reference's position at a key pose"),
)


def bending_angles(skeleton: Skeleton) -> dict[str, str]:
    """Joint name -> the clinical angle of its bending, for the parts that have one."""
    angles = {}
    for part, point in identify(skeleton).items():
        side, _, base = part.partition("_")
        name = ANGLE_OF_PART.get(base if side in ("left", "right") else part)
        if name and point < len(skeleton.names):
            suffix = f"_{side}" if side in ("left", "right") and name != "trunk_flexion" else ""
            angles[skeleton.names[point]] = name + suffix
    return angles


class RuleForm(forms.Form):
    part = forms.ChoiceField(label="Body part")
    direction = forms.ChoiceField(label="When it", choices=DIRECTIONS)
    degrees = forms.IntegerField(
        label="By at least (degrees)",
        min_value=1,
        max_value=180,
        required=False,
        help_text="For a position at a key pose; the analysis measures in steps of 10°.",
    )
    moment = forms.ChoiceField(label="At", required=False)
    sentence = forms.CharField(label="Say", max_length=200)
    said_as = forms.ChoiceField(
        label="Said as",
        choices=(("F", "feedback on the recording"), ("T", "a tip (once per session)")),
        initial="F",
    )

    def __init__(self, *args, exercise, skeleton: Skeleton, **kwargs):
        super().__init__(*args, **kwargs)
        labels = plain_labels(skeleton)
        self.written = written_names(skeleton)
        self.angles = bending_angles(skeleton)
        parts = offered(skeleton, skeleton.names[1:])
        self.fields["part"].choices = sorted(((p, labels[p]) for p in parts), key=lambda c: c[1])
        kinds = type_names(exercise)
        self.fields["moment"].choices = [("", "any key pose")] + [
            (str(k), f"the {name}") for k, name in kinds.items()
        ]

    def clean_sentence(self):
        text = " ".join(self.cleaned_data["sentence"].split())
        if '"' in text:
            raise ValidationError("Leave out double quotes; use single quotes instead.")
        return text

    def clean(self):
        cleaned = super().clean()
        part, direction = cleaned.get("part"), cleaned.get("direction")
        if direction in ("less", "more") and part and part not in self.angles:
            raise ValidationError(
                "The analysis measures no bending angle for this body part; choose "
                "'is away from the reference's position at a key pose'."
            )
        if direction == "away" and not cleaned.get("degrees"):
            self.add_error("degrees", "Give the difference in degrees (1 to 180).")
        return cleaned

    def rule_text(self) -> str:
        """The rule in the feedback language, with a note line saying it was picked."""
        data = self.cleaned_data
        said = f'{data["said_as"]}:"{data["sentence"]}"'
        if data["direction"] in ("less", "more"):
            condition = f"%{data['direction']}${self.angles[data['part']]}"
        else:
            condition = level_condition(self.written[data["part"]], data["degrees"])
            if data.get("moment"):
                condition = f"type${data['moment']} & {condition}"
        return f"{condition} -> {said}"


def level_condition(joint: str, degrees: int) -> str:
    """``@joint$L | … | @joint$4`` for the levels that hold at least ``degrees`` of difference."""
    lowest = min(N_LEVELS, 1 + degrees // LEVEL_STEP_DEG)
    levels = [f"@{joint}${level}" for level in range(lowest, N_LEVELS + 1)]
    return levels[0] if len(levels) == 1 else "(" + " | ".join(levels) + ")"


def appended(grammar: str, rule: str) -> str:
    """The grammar text with the rule as its last line."""
    return (grammar.rstrip("\n") + "\n" if grammar.strip() else "") + rule + "\n"
