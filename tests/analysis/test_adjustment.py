"""Affine offset adjustment on rotations (Alg 13) and the demonstration skeletons (004, 7.3)."""

import csv
from pathlib import Path

import numpy as np
import pytest

from analysis.adjustment.affine import (
    Performance,
    adjust,
    channel_orders,
    demonstration_skeletons,
    frame_jumps,
    gamma_vector,
    water_fill,
)
from analysis.assessment import tutor_mean_poses
from analysis.bvh import read
from analysis.kinematics import forward, rotations
from analysis.kinematics import quaternions as quat
from analysis.landmarks import KeyPoses
from tests.synthetic_motion import SyntheticConfig, generate

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
JUMP = 20.0  # degrees between consecutive frames


def _targets(means, types):
    return np.stack([means[int(t)] for t in types])


@pytest.fixture(scope="module")
def synthetic():
    tutor = generate(SyntheticConfig(n_repetitions=3, noise_deg=0.5), seed=0)
    patient = generate(
        SyntheticConfig(n_repetitions=4, range_of_motion=0.6, noise_deg=1.0, warp=0.3), seed=1
    )
    means = tutor_mean_poses(
        rotations(tutor.motion), tutor.truth.landmark_frames, tutor.truth.landmark_types
    )
    return tutor, patient, means


@pytest.mark.parametrize("method", ["rotation", "euler"])
def test_gamma_zero_is_unchanged_and_one_reaches_the_targets(synthetic, method):
    _, patient, means = synthetic
    q, truth = rotations(patient.motion), patient.truth
    targets = _targets(means, truth.landmark_types)
    frames = truth.landmark_frames
    np.testing.assert_array_equal(adjust(q, frames, targets, 0.0, method), q)
    full = adjust(q, frames, targets, 1.0, method)
    assert quat.angle_between(full[frames], targets, degrees=True).max() < 1e-6
    new = (frame_jumps(full) > JUMP) & (frame_jumps(q) <= JUMP)
    assert not new.any()


def test_partial_gamma_moves_a_share_of_the_way(synthetic):
    _, patient, means = synthetic
    q, truth = rotations(patient.motion), patient.truth
    targets = _targets(means, truth.landmark_types)
    half = adjust(q, truth.landmark_frames, targets, 0.5)
    at = q[truth.landmark_frames]
    full = quat.angle_between(at, targets)
    np.testing.assert_allclose(quat.angle_between(at, half[truth.landmark_frames]), full / 2)
    np.testing.assert_allclose(quat.angle_between(half[truth.landmark_frames], targets), full / 2)


def test_per_joint_gamma_leaves_other_joints_alone(synthetic):
    _, patient, means = synthetic
    q, truth = rotations(patient.motion), patient.truth
    names = patient.motion.skeleton.names
    gamma = gamma_vector({"LeftUpperArm": 1.0}, names)
    out = adjust(q, truth.landmark_frames, _targets(means, truth.landmark_types), gamma)
    arm = names.index("LeftUpperArm")
    np.testing.assert_array_equal(np.delete(out, arm, axis=1), np.delete(q, arm, axis=1))
    assert not np.allclose(out[:, arm], q[:, arm])


def test_offset_is_held_outside_the_landmarks_and_bad_input_is_refused():
    q = quat.from_axis_angle("x", np.radians(np.linspace(0.0, 30.0, 20)))[:, None]
    target = quat.from_axis_angle("y", np.radians([20.0, 20.0]))[:, None]
    out = adjust(q, [5, 12], target, 1.0)
    offsets = quat.multiply(out, quat.conjugate(q))
    np.testing.assert_allclose(offsets[:5], np.repeat(offsets[5:6], 5, axis=0), atol=1e-12)
    np.testing.assert_allclose(offsets[13:], np.repeat(offsets[12:13], 7, axis=0), atol=1e-12)
    with pytest.raises(ValueError, match="distinct"):
        adjust(q, [5, 5], target, 1.0)
    with pytest.raises(ValueError, match="gamma"):
        adjust(q, [5, 12], target, 1.5)
    with pytest.raises(ValueError, match="method"):
        adjust(q, [5, 12], target, 1.0, "affine")


def test_near_gimbal_lock_only_the_euler_version_jumps():
    # X (the middle axis of ZXY) sweeps through 90°: Euler angles flip branch, rotations don't.
    x = 80.0 + 20.0 * np.sin(np.linspace(0.0, np.pi, 61))
    q = quat.from_euler(np.stack([np.full(61, 10.0), x, np.full(61, 5.0)], -1), "ZXY")[:, None]
    frames = np.array([0, 30, 60])
    target = quat.multiply(quat.from_axis_angle("y", np.radians(40.0)), q[frames])
    assert frame_jumps(q).max() < 2.0
    assert frame_jumps(adjust(q, frames, target, 1.0)).max() < 2.0
    assert frame_jumps(adjust(q, frames, target, 1.0, "euler")).max() > JUMP


def _session(name):
    with (DATA / "landmarks.csv").open() as fh:
        row = next(r for r in csv.DictReader(fh) if r["file"] == name)
    frames = np.array(row["frames"].split(";"), dtype=int)
    return read(DATA / name), frames, np.array(row["types"].split(";"), dtype=int)


def test_ui_prmd_session_toward_the_s01_tutor():
    tutor, tutor_frames, tutor_types = _session("sessions/m01_s01_correct.bvh.gz")
    motion, frames, types = _session("sessions/m01_s02_correct.bvh.gz")
    means = tutor_mean_poses(rotations(tutor), tutor_frames, tutor_types)
    q, targets = rotations(motion), _targets(means, types)
    np.testing.assert_array_equal(adjust(q, frames, targets, 0.0), q)
    full = adjust(q, frames, targets, 1.0)
    assert quat.angle_between(full[frames], targets, degrees=True).max() < 1e-5
    before, after = frame_jumps(q), frame_jumps(full)
    # The adjusted jump is at most the input's plus the offset's change over that frame
    # (the rotation distance is invariant under a common left factor) ...
    step = frame_jumps(quat.multiply(full, quat.conjugate(q)))
    assert np.all(after <= before + step + 1e-6)
    # ... and the offsets are timed so that no jump above 20° appears where the input had none,
    assert not ((after > JUMP) & (before <= JUMP)).any()
    # which uniform timing would have broken on this session.
    uniform = frame_jumps(adjust(q, frames, targets, 1.0, max_jump_deg=None))
    assert ((uniform > JUMP) & (before <= JUMP)).any()
    # The paper's Euler version makes jumps out of smooth input on the same session.
    euler = adjust(q, frames, targets, 1.0, "euler", order=channel_orders(motion.skeleton))
    assert ((frame_jumps(euler) > JUMP) & (before <= 10.0)).any()


def test_demonstration_skeletons(synthetic):
    tutor, patient, means = synthetic
    t_perf = Performance.from_motion(
        tutor.motion, KeyPoses.of(tutor.truth.landmark_frames, tutor.truth.landmark_types)
    )
    p_perf = Performance.from_motion(
        patient.motion, KeyPoses.of(patient.truth.landmark_frames, patient.truth.landmark_types)
    )
    sk, n = patient.motion.skeleton, patient.motion.n_frames
    still = demonstration_skeletons(sk, p_perf, t_perf, means, 0.0)
    for positions in (still.patient, still.patient_adjusted, still.tutor, still.tutor_adjusted):
        assert positions.shape == (n, len(sk.names), 3)
    np.testing.assert_array_equal(still.patient_adjusted, still.patient)
    np.testing.assert_array_equal(still.tutor_adjusted, still.tutor)
    # The patient does 4 repetitions, the tutor 3: the tutor moves forwards, and replays itself
    # once, from its last start pose back to its first.
    fmap = still.tutor_frame_map
    assert fmap.shape == (n,)
    back = np.flatnonzero(np.diff(fmap) < 0)
    t_frames = tutor.truth.landmark_frames
    assert back.size == 1 and fmap[back[0]] == t_frames[-1] and fmap[back[0] + 1] <= t_frames[1]

    full = demonstration_skeletons(sk, p_perf, t_perf, means, 1.0, tutor_root="patient")
    lm = p_perf.key_poses.frames
    # γ = 1: the patient takes the tutor's mean poses, the tutor takes the patient's poses.
    expected = forward(sk, _targets(means, p_perf.key_poses.types), p_perf.local_t[lm])[1]
    np.testing.assert_allclose(full.patient_adjusted[lm], expected, atol=1e-6)
    np.testing.assert_allclose(full.tutor_adjusted[lm], full.patient[lm], atol=1e-6)
    np.testing.assert_allclose(full.tutor[:, 0], full.patient[:, 0])
    with pytest.raises(ValueError, match="tutor_root"):
        demonstration_skeletons(sk, p_perf, t_perf, means, 1.0, tutor_root="floor")


@pytest.mark.parametrize("seed", range(5))
def test_water_fill_is_the_most_even_split_within_the_caps(seed):
    rng = np.random.default_rng(seed)
    caps = rng.uniform(0.0, 5.0, 30)
    total = 0.6 * caps.sum()
    steps = water_fill(caps, total)
    assert steps.sum() == pytest.approx(total)
    assert np.all(steps <= caps + 1e-12)
    # Steps below their cap all share one level, the largest step.
    free = steps < caps - 1e-12
    np.testing.assert_allclose(steps[free], steps.max())
    short = water_fill(caps, caps.sum() + 3.0)  # not enough room: the excess is spread evenly
    np.testing.assert_allclose(short - caps, 3.0 / 30)


def test_a_fast_stretch_between_landmarks_gets_less_of_the_offset():
    # 19.5° per frame for 10 frames in the middle of a slow segment, and a 60° offset to apply
    # about the same axis: uniform timing adds 1.2° to every frame's jump.
    speed = np.r_[np.full(20, 1.0), np.full(10, 19.5), np.full(20, 1.0)]
    angles = np.r_[0.0, np.cumsum(speed)]
    q = quat.from_axis_angle("x", np.radians(angles))[:, None]
    frames = np.array([0, 50])
    target = quat.multiply(quat.from_axis_angle("x", np.radians([0.0, 60.0]))[:, None], q[frames])
    before = frame_jumps(q)
    uniform = frame_jumps(adjust(q, frames, target, 1.0, max_jump_deg=None))
    assert (uniform > JUMP).any()
    timed = adjust(q, frames, target, 1.0)
    assert frame_jumps(timed).max() <= JUMP
    np.testing.assert_allclose(
        quat.angle_between(timed[frames], target, degrees=True), 0, atol=1e-9
    )
    offset_steps = frame_jumps(quat.multiply(timed, quat.conjugate(q)))[:, 0]
    assert offset_steps[20:30].max() <= JUMP - before[20:30, 0].min() + 1e-6
