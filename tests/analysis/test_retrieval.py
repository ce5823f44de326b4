"""Paper 002: body-part distance features, 2-bit codes, lookup table, LUT-DTW and retrieval."""

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analysis.bvh import SkeletonMismatchError
from analysis.retrieval.features import (
    FEATURES,
    N_FEATURES,
    frame_features,
    map_joints,
    recording_features,
    resample_frames,
)
from analysis.retrieval.quantised import (
    MotionRetriever,
    code_distance,
    dtw_features,
    dtw_lut,
    frame_codes,
    lookup_table,
    pack,
    quantise,
    unpack,
)

NAMES = (
    "Waist", "Neck", "Head", "LeftUpperArm", "LeftForearm", "LeftHand", "RightUpperArm",
    "RightForearm", "RightHand", "LeftUpperLeg", "LeftLowerLeg", "LeftFoot", "RightUpperLeg",
    "RightLowerLeg", "RightFoot",
)  # fmt: skip
COLUMN = {name: k for k, (name, _, _) in enumerate(FEATURES)}


def stick_figure(abduction: np.ndarray, flexion: np.ndarray, knee: np.ndarray) -> np.ndarray:
    """(F, 15, 3) cm, y up, facing +z: arms raised sideways / forward (rad), knees bent (rad)."""
    frames = len(abduction)
    pos = np.zeros((frames, len(NAMES), 3))
    idx = {n: i for i, n in enumerate(NAMES)}
    for side, sx in (("Left", 1.0), ("Right", -1.0)):
        foot = np.tile([9.0 * sx, 5.0, 0.0], (frames, 1))
        shin = np.stack([0 * knee, np.cos(knee), np.sin(knee)], axis=1)
        thigh = np.stack([0 * knee, np.cos(knee), -np.sin(knee)], axis=1)
        pos[:, idx[f"{side}Foot"]] = foot
        pos[:, idx[f"{side}LowerLeg"]] = foot + 43.0 * shin
        pos[:, idx[f"{side}UpperLeg"]] = foot + 43.0 * (shin + thigh)
    root = 0.5 * (pos[:, idx["LeftUpperLeg"]] + pos[:, idx["RightUpperLeg"]]) + [0.0, 5.0, 0.0]
    pos[:, idx["Waist"]] = root
    pos[:, idx["Neck"]] = root + np.array([0.0, 50.0, 0.0])
    pos[:, idx["Head"]] = root + np.array([0.0, 62.0, 0.0])
    for side, sx in (("Left", 1.0), ("Right", -1.0)):
        arm = np.stack(
            [sx * np.sin(abduction), -np.cos(abduction) * np.cos(flexion), np.sin(flexion)], axis=1
        )
        arm /= np.linalg.norm(arm, axis=1, keepdims=True)
        shoulder = root + np.array([18.0 * sx, 50.0, 0.0])
        pos[:, idx[f"{side}UpperArm"]] = shoulder
        pos[:, idx[f"{side}Forearm"]] = shoulder + 28.0 * arm
        pos[:, idx[f"{side}Hand"]] = shoulder + 53.0 * arm
    return pos


def performance(kind: str, rng: np.random.Generator) -> np.ndarray:
    """A few repetitions of one exercise at 30 fps with random tempo, size, heading and noise."""
    curve = np.concatenate(
        [0.5 - 0.5 * np.cos(np.linspace(0, 2 * np.pi, int(rng.integers(40, 70)))) for _ in range(3)]
    )
    zero = np.zeros_like(curve)
    angles = {
        "abduction": (1.4 * curve, zero, zero),
        "flexion": (zero, 1.4 * curve, zero),
        "squat": (zero, 0.3 * curve, 1.1 * curve),
    }[kind]
    pos = stick_figure(*angles)
    heading = rng.uniform(0, 2 * np.pi)
    turn = np.array(
        [[np.cos(heading), 0, np.sin(heading)], [0, 1, 0], [-np.sin(heading), 0, np.cos(heading)]]
    )
    pos = rng.uniform(0.8, 1.2) * pos @ turn.T + rng.normal(0, 50, 3)
    return pos + rng.normal(0.0, 0.5, pos.shape)


def brute_dtw(dist: np.ndarray) -> float:
    """Textbook DTW on a full (n, m) distance matrix."""
    n, m = dist.shape
    acc = np.full((n + 1, m + 1), np.inf)
    acc[0, 0] = 0.0
    for i in range(n):
        for j in range(m):
            acc[i + 1, j + 1] = dist[i, j] + min(acc[i, j], acc[i, j + 1], acc[i + 1, j])
    return float(acc[n, m])


# ----------------------------------------------------------------------------- features


def test_features_of_a_known_pose():
    zero = np.zeros(1)
    arms_down = frame_features(stick_figure(zero, zero, zero), NAMES)[0]
    size = 12.0 + 50.0 + 86.0  # head–neck + neck–root + leg
    assert arms_down.shape == (N_FEATURES,) == (17,)
    assert arms_down[COLUMN["hands apart"]] == pytest.approx(36.0 / size)
    assert arms_down[COLUMN["left hand in front of the body"]] == pytest.approx(0.0, abs=1e-12)
    forward = frame_features(stick_figure(zero, zero + np.pi / 2, zero), NAMES)[0]
    assert forward[COLUMN["left hand in front of the body"]] == pytest.approx(53.0 / size)
    assert forward[COLUMN["right hand in front of the body"]] == pytest.approx(53.0 / size)


def test_features_ignore_body_size_position_and_heading():
    rng = np.random.default_rng(3)
    pos = performance("squat", rng)
    angle = 1.1
    turn = np.array(
        [[np.cos(angle), 0, np.sin(angle)], [0, 1, 0], [-np.sin(angle), 0, np.cos(angle)]]
    )
    moved = 1.7 * pos @ turn.T + [300.0, 0.0, -40.0]
    np.testing.assert_allclose(frame_features(moved, NAMES), frame_features(pos, NAMES), atol=1e-9)


def test_joint_mapping_by_common_names_and_missing_parts():
    kinect = [
        "SpineBase", "Neck", "Head", "ShoulderLeft", "ElbowLeft", "WristLeft", "HandLeft",
        "ShoulderRight", "ElbowRight", "WristRight", "HandRight", "HipLeft", "KneeLeft",
        "AnkleLeft", "FootLeft", "HipRight", "KneeRight", "AnkleRight", "FootRight",
    ]  # fmt: skip
    found = {role: kinect[i] for role, i in map_joints(kinect).items()}
    assert found["l_hand"] == "HandLeft"
    assert found["l_foot"] == "AnkleLeft"
    assert found["root"] == "SpineBase"
    cmu = ["mixamorig:" + n for n in ("Hips", "Neck", "Head", "LeftShoulder", "LeftArm")]
    with pytest.raises(SkeletonMismatchError, match="left hand"):
        map_joints(cmu)
    generic = ["pelvis", "neck", "head"] + [
        f"{p}_{s}" for s in "lr" for p in ("shoulder", "elbow", "wrist", "hip", "knee", "ankle")
    ]
    found = {role: generic[i] for role, i in map_joints(generic).items()}
    assert found["r_hand"] == "wrist_r"
    assert found["l_shoulder"] == "shoulder_l"


def test_resampling_keeps_duration():
    x = np.arange(31.0)[:, None] * [1.0, 2.0]
    half = resample_frames(x, 30.0, 15.0)
    assert half.shape == (16, 2)
    np.testing.assert_allclose(half[:, 0], np.arange(0, 31, 2))


# ----------------------------------------------------------------------------- codes and table


def test_quantisation_boundaries():
    a = np.array([[-1.5], [-1.0], [-0.5], [0.0], [0.5], [1.0], [1.5]]) * 2.0 + 3.0
    levels = quantise(a, np.array([3.0]), np.array([2.0]))
    assert levels.ravel().tolist() == [0, 1, 1, 2, 2, 3, 3]


@settings(derandomize=True, max_examples=60, deadline=None)
@given(st.integers(1, 8), st.integers(0, 2**31 - 1))
def test_pack_unpack_round_trip(n, seed):
    levels = np.random.default_rng(seed).integers(0, 4, (25, n))
    codes = pack(levels)
    assert codes.min() >= 0
    assert codes.max() < 4**n
    np.testing.assert_array_equal(unpack(codes, n), levels)


def test_pack_puts_the_first_component_in_the_lowest_digit():
    assert pack(np.array([[1, 2, 3]])).tolist() == [1 + 2 * 4 + 3 * 16]


def test_lookup_table_costs():
    c = np.array([0.5, 0.3, 0.2])
    lut = lookup_table(c, dtype=np.float64)
    assert lut.shape == (64, 64)
    np.testing.assert_array_equal(lut, lut.T)
    np.testing.assert_array_equal(np.diag(lut), 0.0)
    base = int(pack(np.array([[0, 0, 0]]))[0])
    for i, ci in enumerate(c):
        for delta, factor in ((1, 1), (2, 4), (3, 16)):
            other = int(base + delta * 4**i)
            assert lut[base, other] == pytest.approx(factor * ci)
    pairs = np.random.default_rng(0).integers(0, 64, (200, 2))
    for a, b in pairs:
        assert lut[a, b] == pytest.approx(code_distance(int(a), int(b), c))


@pytest.mark.parametrize(("n", "m"), [(1, 1), (1, 7), (6, 1), (9, 13), (14, 10), (31, 30)])
def test_lut_dtw_equals_brute_force(n, m):
    rng = np.random.default_rng(n * 100 + m)
    lut = lookup_table(np.array([0.4, 0.3, 0.2, 0.1]))
    a = rng.integers(0, 256, n)
    b = rng.integers(0, 256, m)
    expected = brute_dtw(lut[a][:, b].astype(np.float64))
    assert dtw_lut(a, b, lut) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(("n", "m"), [(1, 5), (8, 3), (17, 20)])
def test_feature_dtw_equals_brute_force(n, m):
    rng = np.random.default_rng(n + m)
    a, b = rng.normal(size=(n, 17)), rng.normal(size=(m, 17))
    dist = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=-1)
    assert dtw_features(a, np.ascontiguousarray(b.T)) == pytest.approx(brute_dtw(dist), rel=1e-9)


# ----------------------------------------------------------------------------- retrieval


@pytest.fixture(scope="module")
def collection():
    rng = np.random.default_rng(11)
    kinds = ("abduction", "flexion", "squat")
    train = [(recording_features(performance(k, rng), NAMES, 30.0), k) for k in kinds * 3]
    test = [(performance(k, rng), k) for k in kinds * 2]
    return train, test


@pytest.mark.parametrize("metric", ["lut", "features"])
def test_identifies_synthetic_exercises(collection, metric):
    train, test = collection
    retriever = MotionRetriever(metric=metric).fit([f for f, _ in train], [k for _, k in train])
    for positions, kind in test:
        assert retriever.identify(recording_features(positions, NAMES, 30.0)) == kind


def test_most_similar_finds_the_recording_itself_first(collection):
    train, _ = collection
    retriever = MotionRetriever().fit([f for f, _ in train], [k for _, k in train])
    found = retriever.most_similar(train[4][0], k=3)
    assert found[0] == (4, 0.0)
    assert [d for _, d in found] == sorted(d for _, d in found)
    assert retriever.labels_[found[1][0]] == train[4][1]


def test_frame_codes_from_positions(collection):
    train, test = collection
    retriever = MotionRetriever(n_components=4).fit([f for f, _ in train], [k for _, k in train])
    positions = test[0][0]
    codes = frame_codes(retriever, positions, NAMES, fps=30.0)
    assert codes.shape == (len(recording_features(positions, NAMES, 30.0)),)
    assert codes.min() >= 0
    assert codes.max() < 4**4
    assert len(np.unique(codes)) > 3


def test_pickle_round_trip(collection):
    train, test = collection
    retriever = MotionRetriever().fit([f for f, _ in train], [k for _, k in train])
    query = recording_features(test[1][0], NAMES, 30.0)
    before = retriever.distances(query)
    blob = pickle.dumps(retriever)
    assert len(blob) < 1_000_000  # the 64 MB table is rebuilt, not stored
    restored = pickle.loads(blob)
    np.testing.assert_array_equal(restored.distances(query), before)
    assert restored.identify(query) == retriever.identify(query)


def test_fit_rejects_bad_input():
    with pytest.raises(ValueError, match="labels"):
        MotionRetriever().fit([np.zeros((5, 17))], ["a", "b"])
    with pytest.raises(ValueError, match="n_components"):
        MotionRetriever(n_components=20).fit(
            [np.random.default_rng(0).normal(size=(30, 17))], ["a"]
        )
