"""The faster forms of the analysis's steps give the bits of the forms they replace."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.adjustment.sync import sample_linear
from analysis.assessment.scoring import repetition_features, repetition_features_all
from analysis.bvh import Motion, Skeleton
from analysis.dtw import cost_matrix, nearest
from analysis.dtw.joint_terms import JointTerms
from analysis.dtw.metrics import kendall_tau_b
from analysis.dtw.nearest import closest_paths
from analysis.kinematics import forward, rotations, translations
from analysis.kinematics.forward_kinematics import forward_positions


def _walk(rng: np.random.Generator, n: int, d: int) -> np.ndarray:
    return np.cumsum(rng.normal(size=(n, d)), axis=0) * 0.01


# The per-pair loop scoring ran before (one `align` call per reference, the first smallest
# cost per path cell), kept in the module as its fallback.
_closest_by_loop = nearest._closest_by_align


@pytest.mark.parametrize("d", [6, 12, 15, 16, 45, 90])
def test_closest_paths_are_the_per_pair_alignments(d: int) -> None:
    # short queries (direct costs), long ones (matrix products), few features (anti-diagonal)
    rng = np.random.default_rng(d)
    refs = [_walk(rng, int(rng.integers(1, 50)), d) for _ in range(7)]
    queries = [_walk(rng, n, d) for n in (1, 3, 7, 8, 9, 40, 65)]
    for x, (k, path) in zip(queries, closest_paths(queries, refs), strict=True):
        k0, path0 = _closest_by_loop(x, refs)
        assert k == k0
        np.testing.assert_array_equal(path, path0)


def test_closest_paths_picks_the_first_of_tied_references() -> None:
    rng = np.random.default_rng(3)
    ref = _walk(rng, 30, 18)
    far = ref + 1.0
    [(k, path)] = closest_paths([ref[::2]], [far, ref, ref.copy()])
    assert k == 1
    assert path[0].tolist() == [0, 0] and path[-1].tolist() == [14, 29]


def test_closest_paths_refuses_mixed_feature_counts() -> None:
    with pytest.raises(ValueError, match="feature count"):
        closest_paths([np.zeros((3, 6))], [np.zeros((3, 9))])


def test_features_of_all_repetitions_are_each_repetitions_features() -> None:
    rng = np.random.default_rng(5)
    templates = [_walk(rng, int(rng.integers(20, 40)), 30) for _ in range(5)]
    segments = [_walk(rng, int(rng.integers(5, 45)), 30) for _ in range(6)]
    together = repetition_features_all(segments, templates)
    for segment, features in zip(segments, together, strict=True):
        assert features.tobytes() == repetition_features(segment, templates).tobytes()


def _unit_quaternions(rng: np.random.Generator, n: int, joints: int) -> np.ndarray:
    q = rng.normal(size=(n, joints, 4))
    return (q / np.linalg.norm(q, axis=-1, keepdims=True)).reshape(n, -1)


def test_joint_terms_give_the_cost_matrix_bits() -> None:
    rng = np.random.default_rng(7)
    for joints in (1, 4, 11):
        x, y = _unit_quaternions(rng, 37, joints), _unit_quaternions(rng, 29, joints)
        y[:5] = x[0]  # identical frames: the terms' min(|dot|, 1) clamp
        terms = JointTerms(x, y)
        for _ in range(3):
            w = np.abs(rng.normal(1.0, 0.3, joints))
            assert terms.costs(w).tobytes() == cost_matrix(x, y, "quaternion", w).tobytes()


def test_joint_terms_refuse_bad_weights_as_the_cost_matrix_does() -> None:
    rng = np.random.default_rng(8)
    terms = JointTerms(_unit_quaternions(rng, 5, 2), _unit_quaternions(rng, 4, 2))
    with pytest.raises(ValueError, match="non-negative"):
        terms.costs(np.array([1.0, -1.0]))


def _kendall_by_numpy(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The former numpy sums: signs of every ordered pair of rows, summed."""
    da, db = np.sign(a[:, None] - a[None]), np.sign(b[:, None] - b[None])
    concordance = np.einsum("ijc,ijc->c", da, db)
    untied = np.count_nonzero(da, axis=(0, 1)) * np.count_nonzero(db, axis=(0, 1))
    return concordance / np.sqrt(np.maximum(untied, 1e-300))


def test_compiled_kendall_tau_gives_the_numpy_sums_bits() -> None:
    rng = np.random.default_rng(9)
    for rows in (1, 2, 17, 96):
        a, b = np.round(rng.normal(size=(rows, 12)), 1), rng.normal(size=(rows, 12))
        a[:, 3] = 0.5  # a constant column: every pair tied
        assert kendall_tau_b(a, b).tobytes() == _kendall_by_numpy(a, b).tobytes()


def test_linear_sampling_gives_the_numpy_expression_bits() -> None:
    rng = np.random.default_rng(10)
    values = rng.normal(size=(50, 7, 3)) * 1e3
    frame_map = rng.uniform(-2.0, 52.0, 80)
    f = np.clip(frame_map, 0.0, 49.0)
    lo = np.minimum(np.floor(f).astype(np.int64), 48)
    w = (f - lo)[:, None, None]
    expected = (1.0 - w) * values[lo] + w * values[lo + 1]
    assert sample_linear(values, frame_map).tobytes() == expected.tobytes()


def test_forward_positions_are_the_forward_passes_positions() -> None:
    rng = np.random.default_rng(11)
    skeleton = Skeleton(
        names=("Hips", "Spine", "Head", "Arm", "Hand"),
        parents=np.array([-1, 0, 1, 1, 3]),
        offsets=rng.normal(size=(5, 3)),
        channels=(("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation",
                   "Yrotation"),) + (("Zrotation", "Xrotation", "Yrotation"),) * 4,
        end_site_parents=np.zeros(0, np.int64), end_site_offsets=np.zeros((0, 3)),
    )  # fmt: skip
    motion = Motion(skeleton, rng.uniform(-90.0, 90.0, (40, 18)), 1 / 30)
    q, t = rotations(motion), translations(motion)
    assert forward_positions(skeleton, q, t).tobytes() == forward(skeleton, q, t)[1].tobytes()
