"""The arm before its elbow: an arm left down is told to rise, not to bend its elbow (issue 26).

In an arm raise whose tutor also bends the elbows (the Bandai-Namco "elderly" and "normal" raises
bend them 80–90° while the arms rise 60–95°), an arm left down loses both its elevation and its
elbow's bend, and the elbow's loss can be the larger: "Bend your left elbow more, by about 84°"
came first, naming a neighbouring joint for an arm that never rose. `arm_first` moves the arm's
own shortfall (a ``less`` finding of a shoulder angle) ahead of the same side's elbow shortfall,
so the first correction says "Raise your left arm higher"; the elbow's stays, after it. Every
other finding keeps its place.
"""

from __future__ import annotations

from collections.abc import Sequence

from analysis.assessment.findings import Finding, joint_of


def _side_joint(finding: Finding) -> tuple[str, str]:
    """("shoulder", "left") of a finding on "shoulder_elevation_left"; ("", "") otherwise."""
    joint, _, side = joint_of(finding.angle).partition("_")
    return (joint, side) if finding.kind == "less" and side else ("", "")


def arm_first(found: Sequence[Finding]) -> list[Finding]:
    """The findings with each arm's ``less`` ahead of the same side's elbow ``less``."""
    out = list(found)
    for finding in found:
        joint, side = _side_joint(finding)
        if joint != "shoulder":
            continue
        elbow = next((i for i, f in enumerate(out) if _side_joint(f) == ("elbow", side)), None)
        if elbow is not None and elbow < out.index(finding):
            out.remove(finding)
            out.insert(elbow, finding)
    return out
