"""Issue 26: an angle (or a limb) the tutor moves differently in every repetition is not what the
exercise trains (`analysis.assessment.findings.unsteady_angles`), so it is not corrected (UI-PRMD
m08: the tutor swings its other arm, elbow 93° ± 22°, while the trained arm's shoulder repeats
66° ± 4°); a plain error is still judged on what the tutor moves most (``Reference.moved``)."""

from __future__ import annotations

from analysis.assessment.findings import (
    Reference,
    RepetitionMeasures,
    findings,
    involved_angles,
    limb_of,
    main_angles,
    plainly_off,
    unsteady_angles,
)

# a shoulder extension of the right arm; the left arm swings by a different amount each time
TUTOR = {"shoulder_flexion_right": 66.0, "shoulder_elevation_right": 38.0,
         "elbow_flexion_left": 93.0, "shoulder_elevation_left": 60.0,
         "shoulder_flexion_left": 42.0}  # fmt: skip
SPREAD = {"shoulder_flexion_right": 4.0, "shoulder_elevation_right": 3.0,
          "elbow_flexion_left": 22.0, "shoulder_elevation_left": 15.0,
          "shoulder_flexion_left": 9.0}  # fmt: skip


def test_limbs_group_a_sides_joints() -> None:
    assert limb_of("elbow_flexion_left") == "arm_left"
    assert limb_of("shoulder_elevation_left") == "arm_left"
    assert limb_of("ankle_dorsiflexion_right") == "leg_right"
    assert limb_of("trunk_flexion") == "trunk"


def test_the_arm_the_tutor_swings_unsteadily_is_not_trained() -> None:
    assert unsteady_angles(TUTOR, SPREAD) == {
        "elbow_flexion_left", "shoulder_elevation_left", "shoulder_flexion_left",
    }  # fmt: skip
    assert involved_angles(TUTOR, spread=SPREAD) == {"shoulder_flexion_right"}
    # without the spread (one repetition, or not known) the larger swing is what it trains
    assert "elbow_flexion_left" in involved_angles(TUTOR)


def test_an_angle_wandering_under_a_steady_joint_is_left_out() -> None:
    # a side lunge: the hip repeats 103° ± 3°, the ankle under it wanders 63° ± 18°
    tutor = {"hip_flexion_right": 103.0, "knee_flexion_right": 91.0,
             "ankle_dorsiflexion_right": 63.0}  # fmt: skip
    spread = {"hip_flexion_right": 3.0, "knee_flexion_right": 4.0,
              "ankle_dorsiflexion_right": 18.0}  # fmt: skip
    assert unsteady_angles(tutor, spread) == {"ankle_dorsiflexion_right"}
    assert involved_angles(tutor, spread=spread) == {"hip_flexion_right", "knee_flexion_right"}


def test_a_limb_with_one_steady_angle_is_kept() -> None:
    # a shoulder rotation: the elbow's range repeats within 19 %, the shoulder's wanders more
    tutor = {"elbow_flexion_right": 30.0, "shoulder_elevation_right": 21.0}
    spread = {"elbow_flexion_right": 5.7, "shoulder_elevation_right": 4.3}
    assert unsteady_angles(tutor, spread) == set()
    assert involved_angles(tutor, spread=spread) == set(tutor)


def test_never_every_moved_limb_is_left_out() -> None:
    tutor = {"knee_flexion_left": 100.0, "knee_flexion_right": 90.0}
    spread = {"knee_flexion_left": 30.0, "knee_flexion_right": 30.0}
    assert unsteady_angles(tutor, spread) == set()
    assert involved_angles(tutor, spread=spread) == set(tutor)


def test_the_swung_arm_is_not_corrected() -> None:
    involved = involved_angles(TUTOR, spread=SPREAD)
    ref = Reference(TUTOR, SPREAD, {}, involved)
    assert main_angles(ref) == {"shoulder_flexion_right"}
    # a patient who does the extension fully and keeps the other arm at the side
    done = {"shoulder_flexion_right": 70.0, "shoulder_elevation_right": 40.0,
            "elbow_flexion_left": 10.0, "shoulder_elevation_left": 5.0}  # fmt: skip
    reps = [RepetitionMeasures(30 * k, done, 1.0, False, {}, 0.5) for k in range(4)]
    assert not plainly_off(reps[0], ref)
    assert [f for f in findings(reps, ref) if f.kind != "good"] == []
    # the same patient with the trained arm at half its excursion fails and is told so
    short = {**done, "shoulder_flexion_right": 30.0}
    reps = [RepetitionMeasures(30 * k, short, 1.0, False, {}, 0.5) for k in range(4)]
    assert plainly_off(reps[0], ref)
    first = findings(reps, ref)[0]
    assert (first.kind, first.angle) == ("less", "shoulder_flexion_right")


def test_a_plain_error_is_judged_on_what_the_tutor_moves_most() -> None:
    ref = Reference(TUTOR, SPREAD, {}, involved_angles(TUTOR, spread=SPREAD),
                    involved_angles(TUTOR))  # fmt: skip
    assert main_angles(ref) == {"elbow_flexion_left"}
    # the swung arm kept still in a repetition that went half way: failed, yet not corrected
    still = {"shoulder_flexion_right": 70.0, "elbow_flexion_left": 10.0}
    reps = [RepetitionMeasures(30 * k, still, 1.0, False, {}, 0.5) for k in range(4)]
    assert plainly_off(reps[0], ref)
    assert [f for f in findings(reps, ref) if f.kind != "good"] == []
