"""Issue 26: the shoulder's axial rotation is corrected where the exercise trains it (the tutor
turns the arm about itself more than it moves anything else: UI-PRMD m09), in words that say to
turn the arm; a leg raise whose tutor's forearms swing, turning the upper arms, is not told about
the arms; the direction the arm is raised in is never corrected (a direction, not an excursion)."""

from __future__ import annotations

from analysis.assessment.findings import involved_angles
from analysis.clinical.labels import INSTRUCTIONS, angle_part

# a shoulder rotation at 90/90: the arm stays up, the forearm swings from outward to inward
ROTATION = {"shoulder_rotation_right": 150.0, "shoulder_elevation_right": 35.0,
            "elbow_flexion_right": 30.0, "shoulder_plane_of_elevation_right": 25.0}  # fmt: skip
# a straight leg raise: the hip moves most; the arms hang, forearms swinging about
LEG_RAISE = {"hip_flexion_right": 85.0, "knee_flexion_right": 20.0,
             "shoulder_rotation_left": 70.0, "shoulder_rotation_right": 60.0,
             "shoulder_plane_of_elevation_left": 80.0}  # fmt: skip


def test_rotation_is_trained_where_the_tutor_turns_the_arm_most() -> None:
    assert involved_angles(ROTATION) == {"shoulder_rotation_right"}
    direction, words = INSTRUCTIONS[("shoulder_rotation", "less")]
    assert direction == "turn" and words.format(part=angle_part("shoulder_rotation_right")) == (
        "Turn your right arm further, swinging the forearm wider"
    )


def test_a_leg_raise_is_not_corrected_on_the_arms_turning() -> None:
    assert involved_angles(LEG_RAISE) == {"hip_flexion_right"}


def test_the_direction_of_raising_is_never_corrected() -> None:
    assert involved_angles({"shoulder_plane_of_elevation_left": 90.0}) == set()
