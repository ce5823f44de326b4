"""Landmark synchronisation (Alg 11) and the tutor frame map (Alg 12, eq 7.17)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analysis.adjustment.sync import (
    sample_linear,
    sample_rotations,
    synchronise_landmarks,
    tutor_frame_map,
)
from analysis.kinematics import quaternions as quat


def test_identical_sequences_pair_one_to_one():
    types = [1, 2, 1, 2, 1]
    assert synchronise_landmarks(types, types) == [(i, i) for i in range(5)]


def test_missing_user_landmark_skips_the_tutor_one():
    # The user's second end of range was not detected: its start pairs with the tutor's last.
    pairs = synchronise_landmarks([1, 2, 1, 1], [1, 2, 1, 2, 1])
    assert pairs == [(0, 0), (1, 1), (2, 2), (3, 4)]


def test_extra_user_landmark_is_left_out_or_reuses_the_tutor():
    user, tutor = [1, 2, 2, 1], [1, 2, 1]
    assert synchronise_landmarks(user, tutor, repeat_tutor=False) == [(0, 0), (1, 1), (3, 2)]
    # Replaying the tutor: the spurious 2 pairs with the same tutor landmark (the tutor waits).
    assert synchronise_landmarks(user, tutor) == [(0, 0), (1, 1), (2, 1), (3, 2)]


def test_reordered_landmarks_match_by_type_cyclically():
    # The tutor does left (2) then right (3); the user right then left.
    assert synchronise_landmarks([1, 3, 2, 1], [1, 2, 3, 1]) == [(0, 0), (1, 2), (2, 1), (3, 3)]


def test_unknown_type_is_not_paired():
    assert synchronise_landmarks([1, 5, 2], [1, 2]) == [(0, 0), (2, 1)]


def test_longer_user_replays_the_tutor_only_when_asked():
    user, tutor = [1, 2, 1, 2, 1], [1, 2, 1]
    assert synchronise_landmarks(user, tutor, repeat_tutor=False) == [(0, 0), (1, 1), (2, 2)]
    assert synchronise_landmarks(user, tutor) == [(0, 0), (1, 1), (2, 2), (3, 1), (4, 2)]


@settings(max_examples=60, derandomize=True, deadline=None)
@given(
    st.lists(st.integers(1, 3), min_size=0, max_size=12),
    st.lists(st.integers(1, 3), min_size=1, max_size=8),
    st.booleans(),
)
def test_pairs_have_equal_types_and_follow_the_user(user, tutor, repeat):
    pairs = synchronise_landmarks(user, tutor, repeat_tutor=repeat)
    assert all(user[u] == tutor[t] for u, t in pairs)
    users = [u for u, _ in pairs]
    assert users == sorted(set(users))
    if not repeat:
        assert len({t for _, t in pairs}) == len(pairs)
    # Every user landmark whose type the tutor has is paired when the tutor can be replayed.
    if repeat:
        assert users == [u for u, k in enumerate(user) if k in tutor]


def test_uniform_stretch_is_eq_7_17():
    # Tutor frames 0..10 stretched over user frames 0..20: user frame i shows tutor frame i/2.
    fmap = tutor_frame_map([(0, 0), (1, 1)], [0, 20], [0, 10], 21)
    np.testing.assert_allclose(fmap, np.arange(21) / 2.0)


def test_map_is_clamped_before_the_first_and_after_the_last_pair():
    fmap = tutor_frame_map([(0, 0), (1, 1)], [5, 15], [3, 8], 20)
    np.testing.assert_array_equal(fmap[:6], 3.0)
    np.testing.assert_array_equal(fmap[15:], 8.0)
    assert fmap[10] == 5.5


def test_landmarks_show_their_partners_and_the_map_moves_forward():
    user_frames, tutor_frames = [0, 12, 30, 41, 60], [0, 10, 20, 30, 40]
    pairs = synchronise_landmarks([1, 2, 1, 2, 1], [1, 2, 1, 2, 1])
    fmap = tutor_frame_map(pairs, user_frames, tutor_frames, 61)
    np.testing.assert_array_equal(fmap[user_frames], tutor_frames)
    assert np.all(np.diff(fmap) >= 0)


def test_wrapping_tutor_is_re_anchored_on_a_same_type_landmark():
    tutor_frames, tutor_types = [0, 10, 20], [1, 2, 1]
    user_frames, user_types = [0, 10, 20, 30, 40], [1, 2, 1, 2, 1]
    pairs = synchronise_landmarks(user_types, tutor_types)
    fmap = tutor_frame_map(pairs, user_frames, tutor_frames, 41, tutor_types=tutor_types)
    # User frames 20..30 go from a start to an end of range: the tutor replays frames 0..10.
    assert fmap[25] == 5.0 and fmap[30] == 10.0 and fmap[35] == 15.0 and fmap[40] == 20.0
    # Without the types the backward segment holds the tutor still.
    held = tutor_frame_map(pairs, user_frames, tutor_frames, 41)
    assert held[25] == 20.0 and held[30] == 10.0


def test_no_pair_is_an_error():
    with pytest.raises(ValueError, match="no synchronised landmark"):
        tutor_frame_map([], [0], [0], 5)


def test_sample_rotations_slerps_between_frames():
    angles = np.array([0.0, 40.0, 80.0])
    q = quat.from_axis_angle("x", np.radians(angles))[:, None, :]  # (3, 1, 4)
    out = sample_rotations(q, np.array([0.0, 0.5, 1.25, 2.0, 7.0]))
    got = np.degrees(2 * np.arctan2(out[:, 0, 1], out[:, 0, 0]))
    np.testing.assert_allclose(got, [0.0, 20.0, 50.0, 80.0, 80.0], atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(out, axis=-1), 1.0)


def test_sample_linear_interpolates_translations():
    values = np.arange(12, dtype=float).reshape(4, 1, 3)
    out = sample_linear(values, np.array([0.5, 3.0]))
    np.testing.assert_allclose(out[:, 0], [[1.5, 2.5, 3.5], [9.0, 10.0, 11.0]])
