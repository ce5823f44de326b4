"""Landmark identification (thesis 004, 5.3–5.4, eqs 5.11, 5.19–5.26) and the exercise model."""

import numpy as np
import pytest
from sklearn.dummy import DummyClassifier
from sklearn.ensemble import AdaBoostClassifier
from sklearn.tree import DecisionTreeClassifier

from analysis.landmarks.detector import (
    Boosted,
    LandmarkDetector,
    frame_types,
    make_classifier,
    training_frames,
    training_observations,
)
from analysis.landmarks.evaluation import evaluate
from analysis.landmarks.identification import (
    FAITHFUL,
    LandmarkModel,
    LandmarkOptions,
    landmark_repetitions,
    periodic_landmarks,
    tutor_cycle,
)
from analysis.landmarks.key_poses import KeyPoses
from analysis.landmarks.signature import pose_series
from tests.synthetic_motion import SyntheticConfig, generate


def test_training_frames_eq_5_11_landmarks_plus_three_times_as_many_others():
    rng = np.random.default_rng(0)
    frames = training_frames(100, [10, 20, 30], 3.0, rng)
    assert frames.size == 3 + 9
    assert {10, 20, 30} <= set(frames.tolist())
    assert np.all(np.diff(frames) > 0)  # distinct and sorted
    assert training_frames(100, [10, 20, 30], 1.0, rng).size == 6  # the prose's "equally sized"


def test_training_frames_never_ask_for_more_frames_than_there_are():
    assert training_frames(5, [0, 1], 3.0, np.random.default_rng(0)).tolist() == [0, 1, 2, 3, 4]


def test_near_negatives_are_drawn_close_to_the_landmarks():
    frames = training_frames(200, [50, 150], 3.0, np.random.default_rng(1), near=1.0)
    negatives = np.setdiff1d(frames, [50, 150])
    distance = np.min(np.abs(negatives[:, None] - np.array([50, 150])[None, :]), axis=1)
    assert negatives.size == 6 and np.all((distance >= 3) & (distance <= 12))


def test_frame_types_eq_5_19():
    assert frame_types(6, [1, 4], [2, 1]).tolist() == [0, 2, 0, 0, 1, 0]


def test_training_observations_are_the_features_at_the_training_frames():
    features = np.arange(40.0).reshape(20, 2)
    x, y = training_observations(features, [3, 9], [1, 2], 2.0, np.random.default_rng(0))
    assert x.shape == (6, 2) and y.shape == (6,)
    rows = (x[:, 0] / 2).astype(int)
    assert y[rows == 3].tolist() == [1] and y[rows == 9].tolist() == [2]
    assert np.sum(y == 0) == 4


@pytest.mark.parametrize("name", ["c45", "svm", "nb"])
@pytest.mark.parametrize("boost", [False, True])
def test_every_classifier_handles_unknown_features(name, boost):
    rng = np.random.default_rng(0)
    x = rng.normal(size=(60, 3))
    y = (x[:, 0] > 0).astype(int) + (x[:, 1] > 1).astype(int)
    x[::7, 2] = np.nan
    model = make_classifier(name, boost).fit(x, y)
    assert model.predict(x).shape == (60,)
    assert np.mean(model.predict(x) == y) > 0.7


def test_c45_is_an_entropy_tree_and_adaboost_wraps_it():
    tree = make_classifier("c45", False)
    assert isinstance(tree, DecisionTreeClassifier) and tree.criterion == "entropy"
    boosted = make_classifier("c45", True)
    assert isinstance(boosted.steps[-1][1], Boosted)
    x = np.random.default_rng(0).normal(size=(40, 2))
    y = (x[:, 0] > 0).astype(int)
    assert isinstance(boosted.fit(x, y).steps[-1][1].model_, AdaBoostClassifier)


def test_boosting_that_cannot_start_keeps_the_lone_learner():
    # a constant guess on four balanced classes is no better than chance: AdaBoost refuses it
    x = np.arange(40.0)[:, None]
    y = np.repeat([0, 1, 2, 3], 10)
    model = Boosted(estimator=DummyClassifier(strategy="most_frequent")).fit(x, y)
    assert isinstance(model.model_, DummyClassifier)
    assert model.predict(x).shape == (40,) and model.classes_.tolist() == [0, 1, 2, 3]


def _wave(n_reps: int, period: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A signature rest → peak → rest per repetition, with its landmark frames and types."""
    rng = np.random.default_rng(seed)
    lengths = rng.integers(int(period * 0.8), int(period * 1.2), n_reps)
    parts = [-np.cos(np.linspace(0, 2 * np.pi, n, endpoint=False)) for n in lengths]
    sig = np.concatenate([*parts, [-1.0]])[:, None]
    starts = np.concatenate([[0], np.cumsum(lengths)])
    peaks = starts[:-1] + lengths // 2
    frames = np.sort(np.concatenate([starts, peaks]))
    types = np.where(np.isin(frames, peaks), 2, 1)
    return sig, frames, types


def test_detector_finds_peaks_and_valleys_of_another_performance():
    sig, frames, types = _wave(6, 40, seed=0)
    # At an extremum the printed features are all 0, a peak looks like a valley: the signature
    # value (extra_features) tells them apart.
    detector = LandmarkDetector(ends=True, extra_features=True).fit([sig], [frames], [types])
    test_sig, test_frames, test_types = _wave(5, 50, seed=1)
    found = detector.candidates(test_sig)
    assert found.frames.size > 0 and set(found.types.tolist()) <= {1, 2}
    for f, t in zip(test_frames, test_types, strict=True):  # every key pose has a candidate
        near = found.types[np.abs(found.frames - f) <= 3]
        assert t in near.tolist()
    assert detector.scores(test_sig).shape == (test_sig.shape[0], 3)


def test_tutor_cycle():
    assert tutor_cycle([1, 2, 1, 2, 1]) == [1, 2]
    assert tutor_cycle([1, 2, 3, 1, 2, 3, 1]) == [1, 2, 3]


@pytest.fixture(scope="module")
def synthetic():
    # short pauses: a start is the first frame of a repetition, anywhere in a long pause would do
    tutor = generate(SyntheticConfig(n_repetitions=4, pause_seconds=0.1), seed=1)
    config = SyntheticConfig(
        n_repetitions=5,
        tempo_jitter=0.2,
        warp=0.3,
        range_of_motion=0.8,
        noise_deg=1.0,
        pause_seconds=0.1,
    )
    patient = generate(config, seed=2)
    sides = SyntheticConfig(n_repetitions=3, sides=("right",), pause_seconds=0.1)
    other_side = generate(sides, seed=3)
    return tutor, patient, other_side


def _check(model, performance, tolerance=4):
    """The detected sequence has the true types, each within ``tolerance`` frames."""
    truth = performance.truth
    result = model.detect(performance.motion)
    found = result.landmarks
    assert found.types.tolist() == truth.landmark_types.tolist()
    assert np.abs(found.frames - truth.landmark_frames).max() <= tolerance
    data = pose_series(performance.motion).reshape(performance.motion.n_frames, -1)
    c = evaluate(found.frames, found.types, truth.landmark_frames, truth.landmark_types, data)
    assert c.precision >= 0.6  # the synthetic starts sit at the motion onset: tight intervals
    return result


def test_model_from_the_tutor_alone_finds_a_patients_key_poses(synthetic):
    tutor, patient, _ = synthetic
    model = LandmarkModel(options=LandmarkOptions(augment=2))
    model.fit(tutor.motion, tutor.truth.landmark_frames, tutor.truth.landmark_types)
    assert model.cycle_ == [1, 2] and model.patterns_ == [[1, 2, 1]]
    assert 2 in model.extreme_types_  # the end of range is the farthest pose from the start
    result = _check(model, patient)
    assert result.refined.frames.size <= result.candidates.frames.size


@pytest.mark.parametrize("side", ["variance", "landmarks"])
def test_model_handles_the_other_side(synthetic, side):
    tutor, patient, other_side = synthetic
    model = LandmarkModel(options=LandmarkOptions(augment=0, side=side))
    model.fit(tutor.motion, tutor.truth.landmark_frames, tutor.truth.landmark_types)
    assert _check(model, other_side).mirrored
    assert not model.detect(patient.motion).mirrored


def test_the_faithful_configuration_runs_with_training_recordings(synthetic):
    tutor, patient, other_side = synthetic
    model = LandmarkModel(options=FAITHFUL)
    training = [(patient.motion, patient.truth.landmark_frames, patient.truth.landmark_types)]
    model.fit(tutor.motion, tutor.truth.landmark_frames, tutor.truth.landmark_types, training)
    result = model.detect(patient.motion)
    assert not result.mirrored and result.landmarks is result.refined
    assert model.detect(other_side.motion).candidates.frames.size == 0  # no mirroring in 2015
    assert result.candidates.frames.size >= result.refined.frames.size > 0


@pytest.mark.parametrize(
    ("frames", "types"),
    [([5, 3], [1, 2]), ([0, 10_000], [1, 2]), ([0, 5], [1]), ([0, 5], [0, 1]), ([3], [1])],
)
def test_bad_tutor_landmarks_are_refused(synthetic, frames, types):
    tutor = synthetic[0]
    with pytest.raises(ValueError, match="landmark"):
        LandmarkModel().fit(tutor.motion, frames, types)


def test_periodic_landmarks_drop_an_out_of_sequence_member():
    # a three-pose cycle 1 → 2 → 3 → 1 with a 3 detected too early in the second repetition
    found = KeyPoses(np.arange(0, 80, 10), np.array([1, 2, 3, 1, 3, 2, 3, 1]))
    kept = periodic_landmarks(found, [[1, 2, 3, 1]])
    assert kept.types.tolist() == [1, 2, 3, 1, 2, 3, 1]
    assert kept.frames.tolist() == [0, 10, 20, 30, 50, 60, 70]
    empty = KeyPoses(np.zeros(0, np.int64), np.zeros(0, np.int64))
    assert periodic_landmarks(empty, [[1, 2, 3, 1]]).frames.size == 0


def test_repetitions_from_a_patients_landmarks(synthetic):
    tutor, patient, _ = synthetic  # the tutor does 4 repetitions, the patient 5
    model = LandmarkModel(options=LandmarkOptions(augment=2))
    model.fit(tutor.motion, tutor.truth.landmark_frames, tutor.truth.landmark_types)
    result = landmark_repetitions(model, patient.motion)
    reps = result.repetitions
    assert len(reps) == patient.truth.rep_starts.size == 5 and all(r.complete for r in reps)
    assert np.abs([r.start for r in reps] - patient.truth.rep_starts).max() <= 4
    assert result.landmarks.frames.size <= result.detection.landmarks.frames.size


def test_repetitions_of_a_cut_recording_end_incomplete(synthetic):
    tutor, patient, _ = synthetic
    model = LandmarkModel(options=LandmarkOptions(augment=2))
    model.fit(tutor.motion, tutor.truth.landmark_frames, tutor.truth.landmark_types)
    truth = patient.truth
    cut = int(truth.landmark_frames[-2]) + 3  # just after the last end of range
    reps = landmark_repetitions(
        model, patient.motion.with_frames(patient.motion.frames[:cut]), method=None
    ).repetitions
    assert len(reps) == 5 and not reps[-1].complete and reps[-1].end == cut - 1
