"""Motion signature (thesis 004, 5.2, eqs 5.1–5.8): smoothing, PCA from the tutor, joints, sides."""

import numpy as np
import pytest

from analysis.landmarks.signature import (
    MotionSignature,
    SignatureOptions,
    augmented_copies,
    joint_series,
    mirror_index,
    moving_joints,
    n_components_for,
    pca_loadings,
    pose_series,
    smooth,
)
from tests.synthetic_motion import SyntheticConfig, generate


@pytest.fixture(scope="module")
def tutor():
    return generate(SyntheticConfig(n_repetitions=3), seed=1)


@pytest.fixture(scope="module")
def right_side():
    config = SyntheticConfig(n_repetitions=3, sides=("right",), tempo_jitter=0.2, noise_deg=0.5)
    return generate(config, seed=2)


def test_smoothing_keeps_a_constant_and_the_length():
    data = np.full((50, 3), 7.0)
    np.testing.assert_allclose(smooth(data, 12.0), data)


def test_smoothing_follows_a_slow_wave_and_removes_fast_noise():
    t = np.arange(300.0)
    slow = np.sin(2 * np.pi * t / 120.0)[:, None]
    noise = np.random.default_rng(0).normal(0.0, 0.2, slow.shape)
    out = smooth(slow + noise, 12.0)  # ω = 0.4 s at 30 fps
    assert out.shape == slow.shape
    assert np.abs(out - slow)[20:-20].max() < 0.2
    assert np.std(out - slow) < 0.4 * np.std(noise)  # about 1/√12 of the noise is left


def test_too_short_a_series_is_left_as_it_is():
    data = np.arange(10.0)[:, None]
    np.testing.assert_allclose(smooth(data, 12.0), data)


def test_eq_5_8_components_up_to_90_percent_by_hand():
    eigen = np.array([1.0, 6.0, 3.0])  # ρ sorted: 0.6, 0.3, 0.1 → cumulative 0.6, 0.9, 1.0
    assert n_components_for(eigen, 0.5) == 1
    assert n_components_for(eigen, 0.9) == 2
    assert n_components_for(eigen, 0.95) == 3


def test_pca_loadings_eqs_5_2_to_5_4():
    rng = np.random.default_rng(0)
    t = rng.normal(size=200)
    x = np.column_stack([t, 2 * t, np.zeros_like(t)]) + rng.normal(0, 0.01, (200, 3)) + 5.0
    means, w, eigen = pca_loadings(x)
    np.testing.assert_allclose(means, x.mean(axis=0))
    np.testing.assert_allclose(w.T @ w, np.eye(3), atol=1e-12)  # orthonormal loadings
    np.testing.assert_allclose(np.abs(w[:, 0]), np.array([1, 2, 0]) / np.sqrt(5), atol=1e-3)
    assert eigen[0] > 100 * eigen[1] and np.all(np.diff(eigen) <= 0)
    scores = (x - means) @ w  # T = X W
    np.testing.assert_allclose(scores.var(axis=0, ddof=1), eigen, rtol=1e-9)


def test_moving_joints_picks_the_most_moving_never_a_still_one():
    series = np.zeros((30, 5, 3))
    series[:, 1, 0] = np.sin(np.arange(30))
    series[:, 3, 1] = 3 * np.sin(np.arange(30))
    series[:, 4, 2] = 0.1 * np.sin(np.arange(30))
    assert moving_joints(series, 2) == (1, 3)
    assert moving_joints(series, 10) == (1, 3, 4)


def test_the_tutor_signature_is_standardised_and_projects_eq_5_5(tutor):
    model = MotionSignature(options=SignatureOptions(scaling="tutor")).fit(tutor.motion)
    names = [tutor.motion.skeleton.names[j] for j in model.joints_]
    assert all(n.startswith("Left") for n in names)  # the left arm moves in this exercise
    sig = model.transform(tutor.motion)
    assert sig.shape == (tutor.motion.n_frames, model.loadings_.shape[1])
    np.testing.assert_allclose(sig.std(axis=0, ddof=1), 1.0, rtol=1e-9)
    c = model.smoothed(tutor.motion)
    np.testing.assert_allclose(sig, (c - model.means_) @ model.loadings_ / model.scale_)
    assert np.sum(model.explained_[: sig.shape[1]]) / model.explained_.sum() >= 0.9


def test_self_scaling_gives_zero_mean_unit_variance(tutor, right_side):
    model = MotionSignature(options=SignatureOptions(scaling="self", mirror=True)).fit(tutor.motion)
    sig = model.transform(right_side.motion)
    np.testing.assert_allclose(sig.mean(axis=0), 0.0, atol=1e-9)
    np.testing.assert_allclose(sig.std(axis=0), 1.0, rtol=1e-9)


def test_mirror_index_swaps_left_and_right(tutor):
    names = tutor.motion.skeleton.names
    swapped = [names[j] for j in mirror_index(names)]
    assert swapped[names.index("LeftForearm")] == "RightForearm"
    assert swapped[names.index("Spine")] == "Spine"


def test_the_other_side_is_recognised_and_mirrored(tutor, right_side):
    model = MotionSignature(options=SignatureOptions(mirror=True)).fit(tutor.motion)
    assert model.mirrored(right_side.motion)
    assert not model.mirrored(tutor.motion)
    plain = MotionSignature(options=SignatureOptions(mirror=False)).fit(tutor.motion)
    # Mirrored, the right arm's movement lands on the tutor's components; unmirrored it does not.
    mirrored_range = np.ptp(model.smoothed(right_side.motion) @ model.loadings_, axis=0)[0]
    plain_range = np.ptp(plain.smoothed(right_side.motion) @ plain.loadings_, axis=0)[0]
    assert mirrored_range > 5 * plain_range


def test_quaternion_source_is_sign_continuous(tutor):
    q = joint_series(tutor.motion, "quaternions")
    assert np.all(np.sum(q[1:] * q[:-1], axis=-1) > 0)
    model = MotionSignature(options=SignatureOptions(source="quaternions")).fit(tutor.motion)
    assert model.transform(tutor.motion).shape[1] >= 1


def test_pose_series_shape(tutor):
    assert pose_series(tutor.motion).shape == (tutor.motion.n_frames, 15, 3)


def test_augmented_copies_move_the_landmarks_with_the_warp(tutor):
    data = np.sin(np.linspace(0, 6 * np.pi, 300))[:, None] * 10.0
    frames = np.array([0, 25, 75, 125, 175, 225, 275, 299])
    types = np.array([1, 2, 1, 2, 1, 2, 1, 1])
    copies = augmented_copies(data, frames, types, copies=3, seed=0)
    assert len(copies) == 3
    for copy, f, t in copies:
        assert 0.8 * 300 - 1 <= len(copy) <= 1.25 * 300 + 1
        assert np.all(np.diff(f) > 0) and f[-1] < len(copy)
        assert t.tolist() == types[: len(t)].tolist()
        # the reduced range: never farther from the rest pose than the original
        rest = data[frames[types == 1]].mean()
        assert np.abs(copy - rest).max() <= np.abs(data - rest).max() * 1.05
        # a peak stays a peak
        peaks = f[t == 2]
        assert np.all(copy[peaks, 0] > rest + 3.0)
