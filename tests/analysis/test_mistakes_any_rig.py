"""The mistakes made on purpose for `bench.eval_mistakes_bandai` are made by body roles, so they
do what they say on a rig that names its joints otherwise and whose rest pose is no posture (a
UI-PRMD session re-expressed on a Bandai-Namco-style rig, `tests.analysis.bandai_style`): the arm
left down no longer rises, the trunk leans 20° further forward, the rest is unchanged."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import read
from analysis.clinical import angle_series
from analysis.feedback.advice import Correction
from bench.eval_mistakes_bandai import arm_down, forward_lean, right_words
from tests.analysis.bandai_style import bandai_style

SESSION = Path(__file__).resolve().parents[2] / "data/ui-prmd/sessions/m07_s02_correct.bvh.gz"


@pytest.fixture(scope="module")
def motion():  # a shoulder abduction of the right arm, on the other rig
    whole = read(SESSION)
    return bandai_style(whole.with_frames(whole.frames[:600]))


def _spread(series: dict[str, np.ndarray], name: str) -> float:
    return float(np.nanmax(series[name]) - np.nanmin(series[name]))


def test_the_arm_left_down_no_longer_rises_and_the_other_is_unchanged(motion) -> None:
    before = angle_series(motion)
    after = angle_series(arm_down(motion, "right"))
    assert _spread(before, "shoulder_elevation_right") > 60.0
    assert _spread(after, "shoulder_elevation_right") < 1.0
    np.testing.assert_allclose(
        after["shoulder_elevation_left"], before["shoulder_elevation_left"], atol=1e-6
    )


def test_the_trunk_leans_20_degrees_further_forward_all_through(motion) -> None:
    changed, truth = forward_lean(motion)
    before = angle_series(motion)["trunk_flexion"]
    after = angle_series(changed)["trunk_flexion"]
    assert truth == pytest.approx(20.0, abs=1.0)
    assert np.nanmedian(after - before) == pytest.approx(20.0, abs=1.0)
    assert np.nanmin(after - before) > 15.0  # every frame, not only on average


def test_a_correction_counts_only_with_the_right_side_part_and_direction() -> None:
    def said(part: str, direction: str) -> Correction:
        return Correction("", part, direction, 90.0, "°", (1,), 0, "")

    assert right_words("arm down", "right", said("right arm", "raise"))
    assert not right_words("arm down", "right", said("left arm", "raise"))
    assert not right_words("arm down", "right", said("right elbow", "bend"))
    assert right_words("lean", "", said("trunk", "straighten"))
    assert not right_words("lean", "", said("left arm", "lower"))
    assert not right_words("too fast", "", None)
