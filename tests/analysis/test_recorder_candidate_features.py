"""The array helpers `bench.eval_recorder_candidates` measures cross-recorder candidates with
(bench/recorder_candidate_features.py), and its session score and AUC, on small synthetic
skeletons whose answer is known."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.clinical.body import Body
from bench.eval_recorder_candidates import from_start, mean_auc, session_score
from bench.recorder_candidate_features import (
    bridge_jumps,
    capped_mean,
    carried,
    jumping_joints,
    low_passed,
    trimmed_mean,
)

FPS = 30.0
# pelvis, chest, shoulder, hip left, hip right
BODY = Body(
    joints={"pelvis": 0, "chest": 1, "shoulder_left": 2, "hip_left": 3, "hip_right": 4},
    pelvis=None,
    thorax=None,
)


def trunk_bending(frames: int) -> np.ndarray:
    """(F, 5, 3): a trunk bending forward by up to 60°, a shoulder carried rigidly 0.1 to the
    side and 0.02 below the chest, hips on the x axis."""
    angle = np.linspace(0.0, np.pi / 3, frames)
    up = np.stack([np.zeros(frames), np.cos(angle), np.sin(angle)], axis=1)
    points = np.zeros((frames, 5, 3))
    points[:, 1] = 0.3 * up
    points[:, 2] = points[:, 1] + np.array([0.1, 0.0, 0.0]) - 0.02 * up
    points[:, 3] = [-0.05, 0.0, 0.0]
    points[:, 4] = [0.05, 0.0, 0.0]
    return points


def test_carried_shoulder_keeps_a_rigid_one_and_removes_a_shrug():
    rigid = trunk_bending(40)
    assert np.allclose(carried(rigid, BODY, ("shoulder_left",)), rigid, atol=1e-9)
    shrugged = rigid.copy()
    shrugged[10:20, 2, 1] += 0.03  # the shoulder girdle lifts for a while
    back = carried(shrugged, BODY, ("shoulder_left",))
    assert np.allclose(back[:, 2], rigid[:, 2], atol=1e-9)
    assert np.allclose(back[:, :2], shrugged[:, :2])  # the other joints are left as they are


def test_a_rig_without_the_joint_is_left_alone():
    points = trunk_bending(10)
    assert np.array_equal(carried(points, BODY, ("collar_left",)), points)


def test_a_held_then_jumping_joint_is_bridged_and_flagged():
    frames = 30
    points = np.zeros((frames, 2, 3))
    points[:, 0, 0] = np.linspace(0.0, 0.1, frames)  # moves smoothly (0.1 body sizes/s)
    points[:, 1, 0] = np.linspace(0.0, 0.1, frames)
    points[10:15, 1, 0] = points[10, 1, 0]  # held...
    points[15:, 1, 0] += 0.2  # ...then jumps 0.2 body sizes in one frame (6 body sizes/s)
    out, count = bridge_jumps(points, FPS)
    assert count == 5  # the jump's frame and the four held frames before it
    assert np.array_equal(out[:, 0], points[:, 0])
    assert np.abs(np.diff(out[:, 1, 0])).max() < 0.2
    assert jumping_joints(points, FPS, 1.5).tolist() == [False, True]
    assert jumping_joints(out, FPS, 1.5).tolist() == [False, False]  # bridged: no step left


def test_low_pass_smooths_a_spike_and_keeps_a_still_joint():
    points = np.ones((31, 1, 3))
    spiky = points.copy()
    spiky[15] += 1.0
    assert np.allclose(low_passed(points, FPS), points)
    assert low_passed(spiky, FPS)[15, 0, 0] < 1.5
    assert low_passed(spiky, FPS).sum() == pytest.approx(spiky.sum())


def test_a_joint_excess_is_capped_or_left_out():
    over = np.array([0.0, 1.0, 10.0])
    assert capped_mean(over, 2.0) == pytest.approx(1.0)
    assert trimmed_mean(over, 1) == pytest.approx(0.5)
    assert trimmed_mean(np.array([4.0]), 1) == pytest.approx(4.0)  # one joint is kept


def test_start_pose_from_several_frames():
    rows = np.arange(12.0).reshape(6, 2)
    assert np.array_equal(from_start(rows, 1), rows - rows[0])
    assert np.allclose(from_start(rows, 3)[1], 0.0)  # the mean of the first three is the second


def test_median_repetition_ignores_one_lost_repetition():
    good, lost = (0.5, 0.0), (10.0, 0.0)
    parts = [good, good, lost]
    assert session_score(parts, 1.5, "median") == pytest.approx(session_score([good], 1.5))
    assert session_score(parts, 1.5) < session_score([good], 1.5) - 20


def test_mean_auc_is_taken_per_group():
    rows = [("a", 0.9, True), ("a", 0.1, False), ("b", 0.2, True), ("b", 0.8, False)]
    assert mean_auc(rows) == pytest.approx(0.5)
    assert mean_auc(rows[:2]) == pytest.approx(1.0)
