"""Issue 26: an arm left down is told to rise before its elbow is told to bend."""

from __future__ import annotations

from analysis.assessment.findings import Finding, RepetitionMeasures, findings
from analysis.assessment.limbs import arm_first
from analysis.feedback import Grammar, default_grammar
from analysis.feedback.advice import advise


def _less(angle: str, amount: float) -> Finding:
    return Finding("less", angle, amount, amount, 0.0, (1,), 0, 1.0)


def test_the_arms_shortfall_comes_before_the_same_sides_elbow() -> None:
    elbow, arm = _less("elbow_flexion_left", 90.0), _less("shoulder_elevation_left", 84.0)
    knee = _less("knee_flexion_right", 95.0)
    assert arm_first([knee, elbow, arm]) == [knee, arm, elbow]
    # the other side's elbow, an elbow bent too far, or an arm already first keep their places
    right = _less("elbow_flexion_right", 90.0)
    more = Finding("more", "elbow_flexion_left", 90.0, 10.0, 100.0, (1,), 0, 1.0)
    assert arm_first([right, arm]) == [right, arm]
    assert arm_first([more, arm]) == [more, arm]
    assert arm_first([arm, elbow]) == [arm, elbow]


def test_a_raise_whose_tutor_bends_the_elbows_tells_the_arm_left_down_to_rise() -> None:
    # the tutor raises both arms 84–90° and bends both elbows 90° (a Bandai-Namco "normal" raise);
    # the patient's left arm stays down: its elbow loses more degrees than its elevation
    tutor = {"shoulder_elevation_left": 84.0, "shoulder_elevation_right": 90.0,
             "elbow_flexion_left": 90.0, "elbow_flexion_right": 90.0}  # fmt: skip
    own = {"shoulder_elevation_left": 0.0, "shoulder_elevation_right": 88.0,
           "elbow_flexion_left": 0.0, "elbow_flexion_right": 89.0}  # fmt: skip
    rep = RepetitionMeasures(0, own, 1.0)
    found = findings([rep], tutor)
    assert found[0].angle == "elbow_flexion_left"  # by size alone, the neighbouring joint
    grammar = Grammar.parse(default_grammar(["LeftArm"], ["start", "top"]))
    first = advise(grammar, arm_first(found), 1).corrections[0]
    assert (first.part, first.direction) == ("left arm", "raise")
    assert first.text.startswith("Raise your left arm higher, by about 84°")
