"""The frame classifier of candidate landmark identification (paper 004, section 5.4).

A multi-class classifier labels every frame of a performance with a landmark type or 0 (*none*)
from the frame-wise features of its motion signature. It is trained on the ground-truth landmark
frames of the training samples (the tutor, and any labelled recordings) plus ``ratio`` times as
many other frames drawn at random (eq 5.11; the thesis's prose says "equally sized", its equation
says 3×, so the ratio is a parameter with the equation's value as default).

Classifiers (5.4.4): "c45" (decision tree, entropy criterion, ≥ 2 samples per leaf, as Weka's J48),
"svm" (linear-kernel SVC, C = 1, one-vs-one, as Weka's SMO with a degree-1 polynomial kernel, on
standardised features: the thesis turned SMO's normalisation off, but unscaled frame widths make
libsvm converge very slowly) and
"nb" (Gaussian naive Bayes), each optionally inside AdaBoost (SAMME, 10 rounds as Weka's default).
Unknown feature values (NaN) go natively to the lone decision tree (as C4.5 handles missing values);
the other learners see them replaced by the training mean plus a missing-value indicator column.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np
import numpy.typing as npt
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.ensemble import AdaBoostClassifier
from sklearn.impute import SimpleImputer
from sklearn.naive_bayes import GaussianNB
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC
from sklearn.tree import DecisionTreeClassifier

from analysis.landmarks.features import frame_features
from analysis.landmarks.key_poses import KeyPoses

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
ClassifierName = Literal["c45", "svm", "nb"]
NONE = 0  # the class of frames that are not landmarks


def _near(positives: IntArray, n_frames: int, window: tuple[int, int]) -> IntArray:
    """Frames between window[0] and window[1] frames away from the nearest positive."""
    frames = np.arange(n_frames, dtype=np.int64)
    distance = np.min(np.abs(frames[:, None] - positives[None, :]), axis=1)
    return frames[(distance >= window[0]) & (distance <= window[1])]


def training_frames(
    n_frames: int,
    landmark_frames: npt.ArrayLike,
    ratio: float,
    rng: np.random.Generator,
    *,
    near: float = 0.0,
    window: tuple[int, int] = (3, 12),
) -> IntArray:
    """Eq 5.11: the landmark frames plus round(ratio·|landmarks|) distinct other frames at random.

    near (ours; 0 = the thesis): the share of those negatives drawn among frames ``window``
    frames away from a landmark, so the classifier learns where a key pose is *not* yet.
    Returns the sorted frame indices (at most ``n_frames`` of them).
    """
    positives = np.unique(np.asarray(landmark_frames, dtype=np.int64))
    h = round(ratio * positives.size)
    close = _near(positives, n_frames, window) if near > 0 and positives.size else positives[:0]
    picked = rng.choice(close, size=min(round(near * h), close.size), replace=False)
    others = np.setdiff1d(np.arange(n_frames, dtype=np.int64), np.concatenate([positives, picked]))
    rest = rng.choice(others, size=min(h - picked.size, others.size), replace=False)
    return np.sort(np.concatenate([positives, picked, rest]))


def frame_types(n_frames: int, landmark_frames: npt.ArrayLike, types: npt.ArrayLike) -> IntArray:
    """Eq 5.19: the class of every frame, the landmark's type where there is one, else NONE."""
    out = np.full(n_frames, NONE, dtype=np.int64)
    out[np.asarray(landmark_frames, dtype=np.int64)] = np.asarray(types, dtype=np.int64)
    return out


def training_observations(
    features: FloatArray,
    landmark_frames: npt.ArrayLike,
    types: npt.ArrayLike,
    ratio: float,
    rng: np.random.Generator,
    *,
    near: float = 0.0,
) -> tuple[FloatArray, IntArray]:
    """Eq 5.21 for one sample: (X (n, n_features), y (n,)) at its training frames."""
    n = features.shape[0]
    frames = training_frames(n, landmark_frames, ratio, rng, near=near)
    return features[frames], frame_types(n, landmark_frames, types)[frames]


class Boosted(ClassifierMixin, BaseEstimator):
    """AdaBoost (SAMME) over ``estimator`` that keeps the lone estimator when boosting cannot start
    (its first round is no better than chance), as Weka's AdaBoostM1 does."""

    def __init__(
        self, *, estimator: ClassifierMixin, n_estimators: int = 10, random_state: int = 0
    ) -> None:
        self.estimator = estimator
        self.n_estimators = n_estimators
        self.random_state = random_state

    def fit(self, X: FloatArray, y: IntArray) -> Boosted:
        boost = AdaBoostClassifier(
            clone(self.estimator), n_estimators=self.n_estimators, random_state=self.random_state
        )
        try:
            self.model_ = boost.fit(X, y)
        except ValueError as error:
            if "worse than random" not in str(error):
                raise
            self.model_ = clone(self.estimator).fit(X, y)
        self.classes_ = self.model_.classes_
        return self

    def predict(self, X: FloatArray) -> IntArray:
        return np.asarray(self.model_.predict(X))

    def predict_proba(self, X: FloatArray) -> FloatArray:
        return np.asarray(self.model_.predict_proba(X))


def make_classifier(
    name: ClassifierName, adaboost: bool, n_estimators: int = 10, seed: int = 0
) -> ClassifierMixin:
    """An unfitted scikit-learn classifier for frame-wise features that may contain NaN."""
    base: ClassifierMixin
    if name == "c45":
        base = DecisionTreeClassifier(criterion="entropy", min_samples_leaf=2, random_state=seed)
    elif name == "svm":
        base = SVC(kernel="linear", C=1.0, random_state=seed)
    elif name == "nb":
        base = GaussianNB()
    else:
        raise ValueError(f"unknown classifier {name!r}")
    if adaboost:
        base = Boosted(estimator=base, n_estimators=n_estimators, random_state=seed)
    elif name == "c45":
        return base
    steps: list[object] = [SimpleImputer(strategy="mean", add_indicator=True)]
    if name == "svm":  # on raw widths (frames) and heights libsvm needs ~50 s per fit
        steps.append(StandardScaler())
    return make_pipeline(*steps, base)


class LandmarkDetector(ClassifierMixin, BaseEstimator):
    """Frame classifier over frame-wise features of motion signatures (eqs 5.18–5.26).

    ``fit(signatures, landmark_frames, landmark_types)``: lists of (F_i, k) signatures, their
    ground-truth landmark frames and types (ints ≥ 1). ``predict(signature)`` → (F,) types with 0
    for *none*; ``candidates(signature)`` → `KeyPoses`. Learnt: ``classifier_``, ``classes_``.
    extra_features: also give the classifier the signature values at the frame (the pose), an
    addition to the thesis's features; ends: count the recording's first and last frames as
    extrema instead of leaving their features unknown, strict: nearest extrema strictly before and
    after the frame (both see `analysis.landmarks.features.frame_features`); near: share of
    the negatives drawn close to the landmarks (see `training_frames`).
    """

    def __init__(
        self,
        *,
        classifier: ClassifierName = "c45",
        adaboost: bool = True,
        ratio: float = 3.0,
        n_estimators: int = 10,
        extra_features: bool = False,
        ends: bool = False,
        strict: bool = False,
        near: float = 0.0,
        seed: int = 0,
    ) -> None:
        self.classifier = classifier
        self.adaboost = adaboost
        self.ratio = ratio
        self.n_estimators = n_estimators
        self.extra_features = extra_features
        self.ends = ends
        self.strict = strict
        self.near = near
        self.seed = seed

    def features(self, signature: FloatArray) -> FloatArray:
        """The observation matrix of one signature: (F, n_features)."""
        fwf = frame_features(signature, self.ends, self.strict)
        if self.extra_features:
            return np.hstack([fwf, np.asarray(signature).reshape(fwf.shape[0], -1)])
        return fwf

    def fit(
        self,
        signatures: Sequence[FloatArray],
        landmark_frames: Sequence[npt.ArrayLike],
        landmark_types: Sequence[npt.ArrayLike],
    ) -> LandmarkDetector:
        rng = np.random.default_rng(self.seed)
        parts = [
            training_observations(self.features(s), f, t, self.ratio, rng, near=self.near)
            for s, f, t in zip(signatures, landmark_frames, landmark_types, strict=True)
        ]
        X = np.vstack([p[0] for p in parts])
        y = np.concatenate([p[1] for p in parts])
        model = make_classifier(self.classifier, self.adaboost, self.n_estimators, self.seed)
        self.classifier_ = clone(model).fit(X, y)
        self.classes_ = np.unique(y)
        return self

    def predict(self, signature: FloatArray) -> IntArray:
        """Eq 5.26: the class of every frame of one signature (F, k) → (F,) ints, 0 = none."""
        return np.asarray(self.classifier_.predict(self.features(signature)), dtype=np.int64)

    def scores(self, signature: FloatArray) -> FloatArray:
        """Per-frame class probabilities (F, len(classes_)), columns in ``classes_`` order."""
        return np.asarray(self.classifier_.predict_proba(self.features(signature)))

    def candidates(self, signature: FloatArray) -> KeyPoses:
        """Eq 5.23: the frames classified as a landmark type, with their types."""
        labels = self.predict(signature)
        frames = np.flatnonzero(labels != NONE).astype(np.int64)
        return KeyPoses(frames, labels[frames])
