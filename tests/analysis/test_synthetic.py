"""The synthetic generator is seeded and its ground truth matches the motion it makes."""

import numpy as np

from analysis.kinematics import joint_angles, positions
from tests.synthetic_motion import SyntheticConfig, generate


def test_same_seed_same_performance_other_seed_differs():
    config = SyntheticConfig(noise_deg=1.0, tempo_jitter=0.2, warp=0.3)
    a, b, c = generate(config, seed=1), generate(config, seed=1), generate(config, seed=2)
    np.testing.assert_array_equal(a.motion.frames, b.motion.frames)
    assert not np.array_equal(a.motion.frames, c.motion.frames)


def test_truth_counts_and_orders_repetitions():
    perf = generate(SyntheticConfig(n_repetitions=6, tempo_jitter=0.3), seed=4)
    truth = perf.truth
    assert truth.rep_starts.size == 6
    assert np.all(truth.rep_starts[1:] > truth.rep_ends[:-1])
    assert np.all(np.diff(truth.landmark_frames) > 0)
    assert truth.landmark_types.tolist() == [1, 2] * 6 + [1]


def test_end_of_range_frame_is_where_the_hand_is_highest():
    perf = generate(SyntheticConfig(n_repetitions=3, warp=0.4), seed=5)
    hand = perf.motion.skeleton.index("LeftHand")
    height = positions(perf.motion)[:, hand, 1]
    truth = perf.truth
    for start, end, peak in zip(
        truth.rep_starts, truth.rep_ends, truth.landmark_frames[1::2], strict=True
    ):
        assert start + np.argmax(height[start : end + 1]) == peak


def test_reduced_range_of_motion_reduces_the_joint_excursion():
    full = generate(SyntheticConfig(range_of_motion=1.0), seed=0).motion
    half = generate(SyntheticConfig(range_of_motion=0.5), seed=0).motion
    name = "LeftForearm"  # the angle at the shoulder-elbow-hand chain does not change; use shoulder
    shoulder_full = np.ptp(positions(full)[:, full.skeleton.index(name), 1])
    shoulder_half = np.ptp(positions(half)[:, half.skeleton.index(name), 1])
    assert shoulder_half < 0.7 * shoulder_full


def test_left_right_order_and_types():
    perf = generate(SyntheticConfig(n_repetitions=4, sides=("right", "left")), seed=0)
    assert perf.truth.rep_sides == ("right", "left", "right", "left")
    assert perf.truth.landmark_types.tolist() == [1, 2, 1, 3, 1, 2, 1, 3, 1]


def test_squat_bends_both_knees():
    perf = generate(SyntheticConfig(exercise="squat", n_repetitions=2), seed=0)
    angles = joint_angles(perf.motion)
    for knee in ("LeftLowerLeg", "RightLowerLeg"):
        assert angles[knee].max() == np.float64(180.0) or angles[knee].max() > 179.9
        assert angles[knee].min() < 100.0  # 100° of flexion at the bottom
    hips = positions(perf.motion)[:, 0, 1]
    assert np.ptp(hips) == 0.0  # the root does not move; the legs bend
