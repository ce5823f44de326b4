"""Paper 001's guidance types by the one tempo and reach rule (`analysis.pipeline.gestures`):
tempo against the reference's pace and the patient's own, reach as the involved joints'
angular excursion against the reference's."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from analysis.kinematics import quaternions as quat
from analysis.pipeline.gestures import (
    GuidanceRules,
    Pace,
    pace_guidance,
    reach_series,
    reference_excursion,
    usual_for_patient,
    usual_pace,
)

RULES = GuidanceRules()


def kinds(pace: Pace, own: Pace | None = None) -> list[str]:
    return [kind for kind, _ in pace_guidance(pace, own, RULES)]


def test_a_repetition_like_the_reference_and_the_patient_gets_nothing():
    assert kinds(Pace(1.0, 1.0)) == []
    assert kinds(Pace(1.3, 0.9), own=Pace(1.3, 0.9)) == []


def test_tempo_far_from_the_reference_is_named_whoever_the_patient_is():
    assert kinds(Pace(0.4, 1.0))[0] == "too fast"
    assert kinds(Pace(2.8, 1.0))[0] == "too slow"
    assert kinds(Pace(0.4, 1.0), own=Pace(0.45, 1.0))[0] == "too fast"
    assert kinds(Pace(0.4, 1.0), own=Pace(0.45, 1.0, earlier=True))[0] == "too fast"


def test_tempo_against_the_patients_own_pace():
    # within the reference's band, but 0.6 of the patient's usual repetition: too fast
    assert kinds(Pace(0.9, 1.0), own=Pace(1.5, 1.0)) == ["too fast"]
    assert kinds(Pace(2.2, 1.0), own=Pace(1.4, 1.0)) == ["too slow"]
    # the same repetition is this patient's usual pace and the demonstration's: nothing to say
    assert kinds(Pace(0.9, 1.0), own=Pace(0.9, 1.0)) == []
    # slower than usual but still quicker than the demonstration: not told to speed up
    assert kinds(Pace(0.95, 1.0), own=Pace(0.5, 1.0)) == []


def test_a_usual_pace_softens_the_words_but_never_hides_a_change_from_the_reference():
    """Issue 34: tempo against the reference's repetition time in a first session and after
    one alike; an earlier session's usual pace only says it is usual for this patient."""
    first, usual = None, Pace(1.6, 1.0, earlier=True)
    assert kinds(Pace(1.6, 1.0), first) == ["too slow"]
    assert kinds(Pace(0.6, 1.0), first) == ["too fast"]
    assert kinds(Pace(1.6, 1.0), usual) == ["too slow"]
    assert kinds(Pace(0.62, 1.0), Pace(0.62, 1.0, earlier=True)) == ["too fast"]
    # within 1.6× of the reference, a patient's usual pace is not named again
    assert kinds(Pace(1.45, 1.0), usual) == []
    assert usual_for_patient("too slow", usual, RULES)
    assert not usual_for_patient("too slow", Pace(1.0, 1.0, earlier=True), RULES)
    assert not usual_for_patient("too slow", replace(usual, earlier=False), RULES)


def test_reach_against_the_reference_and_the_patients_own():
    assert kinds(Pace(1.0, 0.3)) == ["incomplete"]
    usual = Pace(1.0, 1.0, earlier=True)
    assert kinds(Pace(1.0, 0.6), own=usual) == ["incomplete"]
    assert kinds(Pace(1.0, 1.3), own=usual) == ["overdone"]
    assert kinds(Pace(1.0, 0.6), own=Pace(1.0, 0.6, earlier=True)) == []


def test_a_first_session_names_a_reach_past_the_reference():
    """Issue 34: a correct take rarely reaches past 1.1 of the tutor's excursion, so a first
    session's repetition reaching 1.3 of it is overdone (it was left alone below 1.6)."""
    assert kinds(Pace(1.0, 1.3)) == ["overdone"]
    assert kinds(Pace(1.0, 1.1)) == []


def test_this_sessions_repetitions_so_far_name_only_a_clear_change():
    """Against the repetitions so far (no earlier session), a repetition of a take's usual
    spread gets nothing; one far quicker or shorter than its neighbours is named."""
    so_far = Pace(1.45, 1.1)
    assert kinds(Pace(1.3, 1.0), own=so_far) == []
    # within the reference's bands, but 0.62 of the usual tempo / 0.53 of the usual reach
    assert kinds(Pace(0.9, 1.0), own=so_far) == ["too fast"]
    assert kinds(Pace(1.3, 0.58), own=so_far) == ["incomplete"]
    # 0.64 of the usual reach: within a take's spread, not past an earlier session's band
    assert kinds(Pace(1.3, 0.7), own=so_far) == []
    assert kinds(Pace(1.3, 0.7), own=replace(so_far, earlier=True)) == ["incomplete"]


def test_the_most_pressing_comes_first():
    both = pace_guidance(Pace(0.5, 0.4), Pace(1.0, 1.0), RULES)
    assert [k for k, _ in both] == ["too fast", "incomplete"]
    assert both[0][1] > both[1][1] > 1.0


def test_usual_pace_is_the_median():
    assert usual_pace([]) is None
    assert usual_pace([Pace(1.0, 0.5), Pace(3.0, 0.7), Pace(1.2, 0.9)]) == Pace(1.2, 0.7)


def bend(degrees: np.ndarray, n_joints: int = 2, moving: int = 0) -> np.ndarray:
    """(n, J, 4): joint ``moving`` turns about x by ``degrees`` per frame, the others stay."""
    q = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (len(degrees), n_joints, 1))
    q[:, moving] = quat.from_axis_angle("X", np.radians(degrees))
    return q


@pytest.mark.parametrize("factor", [0.6, 1.0, 1.3])
def test_reach_is_the_excursion_against_the_reference(factor):
    angles = 80.0 * np.sin(np.linspace(0.0, np.pi, 40))
    still = bend(np.zeros(40))
    tutor = bend(angles)
    reference = reference_excursion(tutor, still, [(0, 39)], 1)
    assert reference[0] == pytest.approx(80.0, abs=0.5)
    series = reach_series(bend(factor * angles), still, reference)
    assert series.max() == pytest.approx(factor, rel=0.02)
    # the same movement with the other side (the mirror image's joint) reaches as far
    mirrored = reach_series(still, bend(factor * angles), reference)
    assert mirrored.max() == pytest.approx(factor, rel=0.02)


def test_once_an_earlier_session_is_known_the_tutor_bands_widen():
    """Half the tutor's reach in a first session is incomplete; for a patient whose earlier
    session reached as far, it is this patient's usual reach and gets nothing."""
    assert kinds(Pace(1.0, 0.5), own=Pace(1.0, 0.5)) == ["incomplete"]
    assert kinds(Pace(1.0, 0.5), own=Pace(1.0, 0.5, earlier=True)) == []
    assert kinds(Pace(1.0, 0.3), own=Pace(1.0, 0.5, earlier=True)) == ["incomplete"]
