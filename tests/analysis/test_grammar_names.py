"""The grammar checker refuses rules that name a body part or key-pose type the exercise lacks
(they would parse and never fire), at the line and column of the name, listing the names it
knows."""

from __future__ import annotations

from pathlib import Path

import pytest

from analysis.feedback import GrammarError, check_names, default_grammar
from analysis.feedback.grammar import parse_rules, rename_joints

GRAMMARS = Path(__file__).parent / "fixtures" / "grammars"
ARM_JOINTS = ("LEFT_SHOULDER", "LEFT_ELBOW", "RIGHT_SHOULDER", "RIGHT_ELBOW")
TYPES = {1: "start", 2: "arms up"}


def arm_raises() -> str:
    return (GRAMMARS / "e5_arm_raises.txt").read_text()


def test_the_thesis_grammar_passes_with_its_exercises_names():
    rules = check_names(arm_raises(), ARM_JOINTS, TYPES)
    assert len(rules) > 10


def test_an_unknown_body_part_is_refused_with_its_line_and_the_known_names():
    text = arm_raises() + 'type$2 & @banana$3 -> F:"Peel it"\n'
    line = len(text.splitlines())
    with pytest.raises(GrammarError) as caught:
        check_names(text, ARM_JOINTS, TYPES)
    error = caught.value
    assert (error.line, error.column) == (line, 10)
    assert "no body part 'banana'" in error.message
    assert "LEFT_ELBOW, LEFT_SHOULDER, RIGHT_ELBOW, RIGHT_SHOULDER" in error.message
    assert str(error).startswith(f"line {line}, column 10: ")


def test_an_unknown_key_pose_type_is_refused_with_the_types_and_their_names():
    text = 'type$1 -> F:"Ready"\n# a comment\ntype$9 -> F:"Never said"\n'
    with pytest.raises(GrammarError) as caught:
        check_names(text, ARM_JOINTS, TYPES)
    assert (caught.value.line, caught.value.column) == (3, 1)
    assert "no key-pose type 9; its types are 1 (start), 2 (arms up)" in caught.value.message


def test_the_name_is_found_on_the_line_a_wrapped_rule_continues_on():
    text = 'type$2 &\n   (@LEFT_ELBOW$2 |\n    @LEFT_WRIST$3) -> T:"Reach"\n'
    with pytest.raises(GrammarError) as caught:
        check_names(text, ARM_JOINTS, [1, 2])
    assert (caught.value.line, caught.value.column) == (3, 5)


def test_body_parts_match_by_their_readable_form():
    text = 'type$2 & @LeftElbow$2 -> F:"Straighten your left arm"\n'
    check_names(text, ARM_JOINTS, [1, 2])


def test_an_unknown_finding_is_refused():
    with pytest.raises(GrammarError, match="no finding 'sideways'"):
        check_names('%sideways$knee_flexion_left -> F:"Hm"\n', ARM_JOINTS, [1, 2])


def test_the_default_grammar_of_a_skeleton_passes():
    joints = ["LeftUpperLeg", "LeftLowerLeg", "Waist"]
    check_names(default_grammar(joints, {1: "start", 2: "end of range"}), joints, [1, 2])


def test_a_syntax_error_is_still_reported_first():
    with pytest.raises(GrammarError, match="line 1"):
        check_names('type$2 & @banana$3 -> F:"unclosed\n', ARM_JOINTS, [1, 2])


def test_earlier_spellings_are_understood_without_being_offered():
    text = 'type$2 & @hips$3 -> F:"Level hips"\ntype$2 & @waist$2 -> F:"Stored earlier"\n'
    assert len(check_names(text, ["hips", "lower_back"], [1, 2], also=["Waist"])) == 2
    with pytest.raises(GrammarError) as refused:
        check_names(text + '@tail$2 -> F:"x"\n', ["hips", "lower_back"], [1, 2], also=["Waist"])
    assert refused.value.line == 3
    assert refused.value.message.endswith("it knows hips, lower_back")


def test_renaming_joints_changes_only_the_body_parts_of_conditions():
    text = (
        'type$2 & (@ hips$3 | @lower_back$2) -> F:"Keep @hips$3 # in the text"  # @hips$4\n'
        '!@waist$2 -> T:"x"\n'
    )
    rig = {"hips": "Waist", "lower_back": "Spine"}
    renamed = rename_joints(text, lambda joint: rig.get(joint, joint))
    assert renamed == (
        'type$2 & (@ Waist$3 | @Spine$2) -> F:"Keep @hips$3 # in the text"  # @hips$4\n'
        '!@waist$2 -> T:"x"\n'
    )
    first, second = parse_rules(renamed)
    assert (first.line, second.line) == (1, 2)  # the layout, so error lines, are kept


def test_syntax_errors_speak_of_body_parts_as_the_page_does():
    with pytest.raises(GrammarError) as unknown:
        check_names('left_knee$3 -> F:"x"\n', ARM_JOINTS, [1, 2])
    assert "@body_part$N for a body part" in unknown.value.message
    with pytest.raises(GrammarError) as missing:
        check_names('type$2 & @ -> F:"x"\n', ARM_JOINTS, [1, 2])
    assert "a body part" in missing.value.message and "joint" not in missing.value.message
