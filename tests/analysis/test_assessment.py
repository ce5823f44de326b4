"""Assessment features, mean poses and the two assessors (004, 7.2)."""

import numpy as np
import pytest
from sklearn.tree import DecisionTreeClassifier

from analysis.assessment.joints import (
    LandmarkAssessor,
    ThresholdAssessor,
    joint_relevance,
    landmark_features,
    mean_quaternion,
    pose_difference_features,
    tutor_mean_poses,
)
from analysis.kinematics import quaternions as quat
from analysis.kinematics import rotations
from tests.synthetic_motion import SyntheticConfig, generate


def test_mean_of_symmetric_rotations_is_their_centre_whatever_the_signs():
    base = quat.from_euler([20.0, -35.0, 50.0], "ZXY")
    spread = quat.from_axis_angle("z", np.radians([-30.0, 30.0, -10.0, 10.0]))
    samples = quat.multiply(base, spread)
    samples[1] *= -1.0  # q and −q are the same rotation
    mean = mean_quaternion(samples)
    assert quat.angle_between(mean, base, degrees=True) < 1e-9
    assert mean[0] >= 0


def test_tutor_mean_poses_per_type():
    q = quat.from_axis_angle("x", np.radians([0.0, 90.0, 2.0, 88.0, -2.0]))[:, None, :]
    means = tutor_mean_poses(np.repeat(q, 3, axis=1), [0, 1, 2, 3, 4], [1, 2, 1, 2, 1])
    assert sorted(means) == [1, 2] and means[1].shape == (3, 4)
    assert np.all(quat.angle_between(means[1], quat.identity((3,)), degrees=True) < 1e-6)
    np.testing.assert_allclose(quat.angle_between(means[2], q[1], degrees=True), 1.0, atol=1e-3)


def test_pose_difference_is_the_relative_rotation_in_degrees():
    reference = quat.from_euler([[10.0, 20.0, 30.0]], "ZXY")[:, None, :]
    user = quat.multiply(reference, quat.from_axis_angle("y", np.radians(30.0)))
    feats = pose_difference_features(user, reference)
    assert feats.shape == (1, 1, 4)
    np.testing.assert_allclose(feats[0, 0], [0.0, 30.0, 0.0, 30.0], atol=1e-9)
    np.testing.assert_allclose(pose_difference_features(reference, reference), 0.0, atol=1e-12)


def test_landmark_features_need_a_mean_pose_for_every_type():
    q = quat.identity((5, 2))
    means = tutor_mean_poses(q, [0, 2], [1, 2])
    assert landmark_features(q, [1, 3], [2, 1], means).shape == (2, 2, 4)
    with pytest.raises(KeyError, match=r"\[3\]"):
        landmark_features(q, [1], [3], means)


@pytest.fixture(scope="module")
def synthetic():
    """A tutor, its mean poses, and landmark features/levels of performances whose range of
    motion (1.0, 0.8, 0.6, 0.4) makes the arm's end-of-range level 1, 2, 3, 4."""
    tutor = generate(SyntheticConfig(n_repetitions=4, noise_deg=0.5), seed=0)
    tq, truth = rotations(tutor.motion), tutor.truth
    means = tutor_mean_poses(tq, truth.landmark_frames, truth.landmark_types)
    names = tutor.motion.skeleton.names
    arm = [names.index("LeftUpperArm"), names.index("LeftForearm")]

    def dataset(seeds):
        xs, ys, ts = [], [], []
        for seed in seeds:
            for level, rom in enumerate([1.0, 0.8, 0.6, 0.4], start=1):
                config = SyntheticConfig(
                    n_repetitions=3, range_of_motion=rom, noise_deg=0.5, tempo_jitter=0.2
                )
                perf = generate(config, seed=seed)
                frames, types = perf.truth.landmark_frames, perf.truth.landmark_types
                xs.append(landmark_features(rotations(perf.motion), frames, types, means))
                y = np.ones((len(frames), len(names)), dtype=int)
                y[np.ix_(types == 2, arm)] = level
                ys.append(y)
                ts.append(types)
        return np.concatenate(xs), np.concatenate(ys), np.concatenate(ts)

    tutor_feats = landmark_features(tq, truth.landmark_frames, truth.landmark_types, means)
    return {
        "means": means, "arm": arm, "train": dataset([1, 2, 3]), "test": dataset([10, 11]),
        "tutor": (tutor_feats, truth.landmark_types),
    }  # fmt: skip


def test_joint_relevance_finds_the_moving_joints(synthetic):
    relevance = joint_relevance(synthetic["means"])
    upper_arm, forearm = synthetic["arm"]
    assert relevance[upper_arm] > 70 and relevance[forearm] > 8
    assert np.delete(relevance, synthetic["arm"]).max() < 3


def test_boosted_tree_assessor_learns_reduced_range_as_higher_levels(synthetic):
    x, y, t = synthetic["train"]
    model = LandmarkAssessor().fit(x, y, t)
    xt, yt, tt = synthetic["test"]
    predicted = model.predict(xt, tt)
    assert predicted.shape == yt.shape and predicted.dtype.kind == "i"
    arm = synthetic["arm"]
    assert np.mean(predicted[:, arm] == yt[:, arm]) >= 0.95
    # Joints that never move were labelled 1 throughout: a constant, not a classifier.
    assert np.all(np.delete(predicted, arm, axis=1) == 1)
    with pytest.raises(ValueError, match="pass types"):
        model.predict(xt)


def test_assessor_is_configurable_and_ignores_missing_labels(synthetic):
    x, y, _ = synthetic["train"]
    y = y.copy()
    y[:, 0] = 0  # no label at all for joint 0
    missing = np.random.default_rng(0).random(len(y)) < 0.4
    y[missing, synthetic["arm"][0]] = 0  # 40 % of the upper arm's labels missing
    model = LandmarkAssessor(estimator=DecisionTreeClassifier(criterion="entropy"))
    model.fit(x, y, None)
    predicted = model.predict(synthetic["test"][0])
    assert np.all(predicted[:, 0] == 0)
    upper_arm = synthetic["arm"][0]
    assert np.mean(predicted[:, upper_arm] == synthetic["test"][1][:, upper_arm]) >= 0.9


def test_threshold_assessor_levels_grow_with_the_deviation():
    model = ThresholdAssessor().fit(np.zeros((4, 2, 4)), [1, 2, 1, 2])
    np.testing.assert_allclose(model.thresholds(1), [[10.0, 20.0, 30.0]] * 2)
    angles = np.linspace(0.0, 60.0, 121)
    feats = np.zeros((len(angles), 2, 4))
    feats[:, :, 3] = angles[:, None]
    levels = model.predict(feats, [2] * len(angles))
    assert np.all(np.diff(levels, axis=0) >= 0)
    assert levels[0, 0] == 1 and levels[-1, 0] == 4
    assert levels[angles.tolist().index(15.0), 0] == 2


def test_threshold_assessor_calibrates_on_the_tutor(synthetic):
    feats, types = synthetic["tutor"]
    model = ThresholdAssessor(floor_deg=1.0).fit(feats, types)
    # Every one of the tutor's own key poses is "as the tutor".
    assert np.all(model.predict(feats, types) == 1)
    # Widths follow the tutor's spread: a noisier tutor gets wider levels.
    noisy = feats.copy()
    noisy[:, :, 3] *= 3.0
    wider = ThresholdAssessor(floor_deg=1.0).fit(noisy, types)
    assert np.all(wider.base_ >= model.base_) and np.any(wider.base_ > model.base_)
    # A type the tutor never had falls back on the pooled widths.
    np.testing.assert_allclose(model.thresholds(9)[:, 0], model.pooled_base_)


def test_threshold_assessor_ranks_reduced_range_below_the_tutor(synthetic):
    model = ThresholdAssessor().fit(*synthetic["tutor"])
    xt, yt, tt = synthetic["test"]
    upper_arm = synthetic["arm"][0]
    levels = model.predict(xt, tt)[tt == 2, upper_arm]
    truth = yt[tt == 2, upper_arm]
    means = [levels[truth == k].mean() for k in (1, 2, 3, 4)]
    assert means == sorted(means) and means[0] == 1 and means[-1] == 4
