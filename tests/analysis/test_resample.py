"""Resampling to another frame rate keeps the poses at the original frame times and interpolates
rotations along the shortest arc."""

import numpy as np
import pytest

from analysis.kinematics import positions, rotations
from analysis.kinematics import quaternions as quat
from analysis.kinematics.resample import resample, sample_times
from tests.synthetic_motion import SyntheticConfig, generate


@pytest.fixture(scope="module")
def motion():
    return generate(SyntheticConfig(n_repetitions=2, noise_deg=1.0, warp=0.3), seed=3).motion


def test_upsampling_keeps_original_frames_exactly(motion):
    up = resample(motion, 4 * motion.fps)
    assert up.fps == pytest.approx(120.0)
    np.testing.assert_allclose(positions(up)[::4], positions(motion), atol=1e-9)


def test_downsampling_takes_every_other_pose(motion):
    down = resample(motion, motion.fps / 2)
    n = down.n_frames
    np.testing.assert_allclose(positions(down), positions(motion)[::2][:n], atol=1e-9)


def test_midpoint_rotation_is_the_slerp_half_way(motion):
    up = resample(motion, 2 * motion.fps)
    q = rotations(motion)
    expected = quat.slerp(q[10], q[11], np.full(q.shape[1], 0.5))
    got = rotations(up)[21]
    np.testing.assert_allclose(np.abs(np.sum(expected * got, axis=-1)), 1.0, atol=1e-9)


def test_angles_stay_continuous_across_the_wrap(motion):
    frames = motion.frames.copy()
    column = int(motion.skeleton.channel_starts[5])
    frames[:, column] = np.linspace(170.0, 190.0, motion.n_frames)  # crosses 180°
    up = resample(motion.with_frames(frames), 3 * motion.fps)
    assert np.max(np.abs(np.diff(up.frames[:, column]))) < 1.0


def test_same_rate_returns_the_motion_and_bad_rate_is_refused(motion):
    assert resample(motion, motion.fps) is motion
    with pytest.raises(ValueError):
        resample(motion, 0.0)


def test_sample_times_cover_the_duration():
    times = sample_times(31, 1 / 30, 120.0)
    assert times[0] == 0.0 and times[-1] == pytest.approx(1.0)
    assert times.size == 121
