"""Candidate landmark identification (paper 004, sections 5.3–5.4).

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

`LandmarkModel` is the exercise-level estimator the pipeline uses: tutor-fitted signature,
classifier, refining, and (ours) grammar typing and relocation; `LandmarkOptions()` is our best
configuration on UI-PRMD, `FAITHFUL` the thesis's C4.5 + AdaBoost + EM + μ1.

    model = LandmarkModel().fit(tutor_motion, tutor_frames, tutor_types, training=[...])
    result = model.detect(motion)            # LandmarkResult; result.landmarks → periodic.clean
    reps = landmark_repetitions(model, motion).repetitions   # detect → GA^K → repetitions

`landmark_repetitions` is the entry point for segmentation (`analysis.segmentation` and the
pipeline): repetitions (start, end-of-range frames, end, complete) from key poses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
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

from analysis.bvh import Motion
from analysis.features import frame_features
from analysis.periodic import clean
from analysis.refining import (
    Candidates,
    GrammarOptions,
    RefineOptions,
    farthest_types,
    mean_poses,
    pose_distances,
    refine,
    regularise,
    relocate,
    transitions,
    typical_gaps,
)
from analysis.repetitions import Repetition, repetitions
from analysis.signature import MotionSignature, SignatureOptions, augmented_copies, pose_series

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
    for *none*; ``candidates(signature)`` → `Candidates`. Learnt: ``classifier_``, ``classes_``.
    extra_features: also give the classifier the signature values at the frame (the pose), an
    addition to the thesis's features; ends: count the recording's first and last frames as
    extrema instead of leaving their features unknown, strict: nearest extrema strictly before and
    after the frame (both see `analysis.features.frame_features`); near: share of
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

    def candidates(self, signature: FloatArray) -> Candidates:
        """Eq 5.23: the frames classified as a landmark type, with their types."""
        labels = self.predict(signature)
        frames = np.flatnonzero(labels != NONE).astype(np.int64)
        return Candidates(frames, labels[frames])


OURS_SIGNATURE = SignatureOptions(window=0.5, scaling="self", mirror=True)
OURS_REFINE = RefineOptions(clustering="gap", selection="mu1", beta=15.0)


@dataclass(frozen=True)
class LandmarkOptions:
    """Everything that configures `LandmarkModel`; the defaults are our best configuration on
    UI-PRMD (docs: eval_landmarks), `FAITHFUL` is the thesis's C4.5 + AdaBoost + EM + μ1.

    grammar: None = no grammar-constrained typing; relocate: move landmarks of types that the
    training data shows at the farthest pose from the preceding landmark there; augment: warped
    tutor copies added to the training data when no labelled recordings are given; side (ours,
    with ``signature.mirror``): choose the straight or mirrored performance by the variance the
    tutor's eigenspace captures ("variance"), or detect on both and keep the side whose final
    landmarks sit closer to the tutor's mean poses of their types ("landmarks", twice the cost).
    """

    signature: SignatureOptions = field(default_factory=lambda: OURS_SIGNATURE)
    classifier: ClassifierName = "c45"
    adaboost: bool = True
    n_estimators: int = 10
    ratio: float = 3.0
    ends: bool = True
    strict: bool = False
    near: float = 0.0
    extra_features: bool = False
    refine: RefineOptions = field(default_factory=lambda: OURS_REFINE)
    grammar: GrammarOptions | None = field(default_factory=GrammarOptions)
    relocate: bool = True
    augment: int = 4
    side: Literal["variance", "landmarks"] = "variance"
    seed: int = 0


FAITHFUL = LandmarkOptions(
    signature=SignatureOptions(window=0.4, scaling="tutor", mirror=False),
    ends=False,
    refine=RefineOptions(clustering="em", selection="mu1", beta=12.0),
    grammar=None,
    relocate=False,
    augment=0,
)

Labelled = tuple[Motion, npt.ArrayLike, npt.ArrayLike]  # recording, landmark frames, types


@dataclass(frozen=True)
class LandmarkResult:
    """Landmarks of one performance at each stage: ``candidates`` (identification, eq 5.23),
    ``refined`` (clustering + selection, eq 5.27), ``landmarks`` (after grammar typing and
    relocation: what periodic sequence analysis receives), ``signature`` (F, k), ``mirrored``."""

    candidates: Candidates
    refined: Candidates
    landmarks: Candidates
    signature: FloatArray
    mirrored: bool


def _checked(
    motion: Motion, frames: npt.ArrayLike, types: npt.ArrayLike
) -> tuple[IntArray, IntArray]:
    """Landmark frames and types as int arrays, after checking they make sense for ``motion``."""
    f, t = np.asarray(frames, dtype=np.int64), np.asarray(types, dtype=np.int64)
    if f.ndim != 1 or f.shape != t.shape or f.size < 2:
        raise ValueError("need at least two landmarks, as many types as frames")
    if np.any(np.diff(f) <= 0) or f[0] < 0 or f[-1] >= motion.n_frames:
        raise ValueError("landmark frames must increase and lie inside the recording")
    if np.any(t < 1):
        raise ValueError("landmark types must be integers from 1")
    return f, t


def _detector(opts: LandmarkOptions) -> LandmarkDetector:
    return LandmarkDetector(
        classifier=opts.classifier,
        adaboost=opts.adaboost,
        ratio=opts.ratio,
        n_estimators=opts.n_estimators,
        extra_features=opts.extra_features,
        ends=opts.ends,
        strict=opts.strict,
        near=opts.near,
        seed=opts.seed,
    )


def tutor_cycle(types: npt.ArrayLike) -> list[int]:
    """One repetition's landmark types in the tutor: up to the return of its first type, e.g.
    [1, 2] for 1, 2, 1, 2, …, 1 (the order `analysis.repetitions` expects)."""
    t = np.asarray(types, dtype=np.int64)
    again = np.flatnonzero(t[1:] == t[0])
    return [int(v) for v in t[: int(again[0]) + 1 if again.size else t.size]]


class LandmarkModel(BaseEstimator):
    """Key-pose model of one exercise: signature, classifier and refining (sections 5.2–5.5).

    ``fit(tutor, frames, types, training=())``: the tutor motion and its landmark frames and types,
    plus optional labelled recordings ``(motion, frames, types)``; without them the classifier
    trains on the tutor and ``options.augment`` warped copies. ``detect(motion)`` →
    `LandmarkResult`. Learnt: ``signature_``, ``detector_``, ``means_`` (tutor mean signature per
    type, eq 5.30), ``allowed_`` (type transitions), ``gaps_`` (typical frames between
    consecutive types, for the grammar's tempo prior), ``extreme_types_``, ``cycle_``, ``patterns_``
    (training periods for `analysis.periodic.clean`).
    """

    def __init__(self, *, options: LandmarkOptions = LandmarkOptions()) -> None:
        self.options = options

    def _samples(
        self, tutor: Labelled, training: Sequence[Labelled]
    ) -> list[tuple[FloatArray, IntArray, IntArray]]:
        sig = self.signature_
        labelled = [tutor, *training]
        out = [
            (sig.transform(m), np.asarray(f, np.int64), np.asarray(t, np.int64))
            for m, f, t in labelled
        ]
        if not training and self.options.augment:
            copies = augmented_copies(
                sig.smoothed(tutor[0], False),
                tutor[1],
                tutor[2],
                self.options.augment,
                self.options.seed,
            )
            out += [(sig.project(c), f, t) for c, f, t in copies]
        return out

    def fit(
        self,
        tutor: Motion,
        frames: npt.ArrayLike,
        types: npt.ArrayLike,
        training: Sequence[Labelled] = (),
    ) -> LandmarkModel:
        """Learn from the tutor (and labelled recordings); raises ValueError on bad landmarks."""
        frames, types = _checked(tutor, frames, types)
        labelled = [(tutor, frames, types), *((m, *_checked(m, f, t)) for m, f, t in training)]
        self.signature_ = MotionSignature(options=self.options.signature).fit(tutor)
        samples = self._samples(labelled[0], labelled[1:])
        self.detector_ = _detector(self.options).fit(*zip(*samples, strict=True))
        self.means_ = mean_poses(samples[0][0], frames, types)
        self.cycle_ = tutor_cycle(types)
        self.patterns_ = [[*self.cycle_, self.cycle_[0]]]
        n_types = max(int(np.max(t)) for _, _, t in labelled)
        self.allowed_ = transitions([t for _, _, t in labelled], n_types)
        self.gaps_ = typical_gaps([(f, t) for _, f, t in labelled], n_types)
        self.extreme_types_ = set()
        if self.options.relocate:
            poses = [(pose_series(m), np.asarray(f), np.asarray(t)) for m, f, t in labelled]
            self.extreme_types_ = farthest_types(poses)
        return self

    def detect(self, motion: Motion) -> LandmarkResult:
        """Candidate, refined and final landmarks of one performance (same fps as the tutor)."""
        if not self.signature_.options.mirror:
            return self._detect_side(motion, False)
        if self.options.side == "landmarks":
            sides = [self._detect_side(motion, m) for m in (False, True)]
            return min(sides, key=self._misfit)
        return self._detect_side(motion, self.signature_.mirrored(motion))

    def _misfit(self, result: LandmarkResult) -> float:
        """Mean distance of the final landmarks to their types' tutor mean signatures (inf if
        none): how well a side's key poses look like the tutor's."""
        found = result.landmarks
        if found.frames.size == 0:
            return float("inf")
        width = int(max(self.means_)) + 1
        distances = pose_distances(result.signature, self.means_, width)
        return float(np.mean(distances[found.frames, found.types]))

    def _detect_side(self, motion: Motion, mirrored: bool) -> LandmarkResult:
        sig = self.signature_.project(self.signature_.smoothed(motion, mirrored))
        candidates = self.detector_.candidates(sig)
        refined = refine(candidates, sig, self.means_, self.options.refine)
        final = refined
        if self.options.grammar is not None:
            final = regularise(
                final, sig, self.means_, self.allowed_, self.options.grammar, gaps=self.gaps_
            )
        if self.extreme_types_:
            final = relocate(final, pose_series(motion), self.extreme_types_)
        return LandmarkResult(candidates, refined, final, sig, bool(mirrored))


def periodic_landmarks(
    landmarks: Candidates, patterns: Sequence[Sequence[int]], method: str = "ga-k", seed: int = 0
) -> Candidates:
    """Chapter 6 on detected landmarks: keep the members `analysis.periodic.clean` keeps.

    patterns: training periods (``LandmarkModel.patterns_``, e.g. [[1, 2, 1]]); method: one of
    `analysis.periodic.METHODS` (GA^K by default). Returns the kept landmarks, in time order.
    """
    if landmarks.frames.size == 0:
        return landmarks
    kept = np.asarray(
        clean([int(t) for t in landmarks.types], patterns, method=method, seed=seed), np.int64
    )
    return Candidates(landmarks.frames[kept], landmarks.types[kept])


@dataclass(frozen=True)
class RepetitionResult:
    """Everything `landmark_repetitions` found in one performance: the detection stages
    (``detection``), the landmarks after periodic analysis (``landmarks``) and the repetitions
    (`analysis.repetitions.Repetition`: start, end-of-range frames, end, complete, cycle)."""

    detection: LandmarkResult
    landmarks: Candidates
    repetitions: list[Repetition]


def landmark_repetitions(
    model: LandmarkModel,
    motion: Motion,
    *,
    method: str | None = "ga-k",
    order: Sequence[int] | Sequence[Sequence[int]] | None = None,
    seed: int = 0,
) -> RepetitionResult:
    """Entry point for segmentation (item 7 of issue 4): repetitions of a performance from its key
    poses — `LandmarkModel.detect`, periodic sequence analysis (`periodic_landmarks`, skipped when
    ``method`` is None), then `analysis.repetitions.repetitions` with the tutor's cycle.

    model: a fitted `LandmarkModel` of the exercise; motion: the performance (the tutor's fps).
    order: the cycles of `analysis.repetitions` (default ``model.cycle_``, e.g. [1, 2]); give one
    cycle per side (``[[1, 2], [3, 4]]``) when the tutor's landmarks have a type set per side, and
    repetitions are matched by type so patients may do the sides in another order. Incomplete
    repetitions (missing start or end of range, cut short by the recording's end) and extra ones
    beyond the tutor's count are all returned.
    """
    found = model.detect(motion)
    kept = found.landmarks
    if method is not None:
        kept = periodic_landmarks(kept, model.patterns_, method, seed)
    cycles = order if order is not None else model.cycle_
    reps = repetitions(
        kept.frames.tolist(), kept.types.tolist(), cycles, last_frame=motion.n_frames - 1
    )
    return RepetitionResult(found, kept, reps)
