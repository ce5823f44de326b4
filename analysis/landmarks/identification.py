"""Candidate landmark identification for an exercise (paper 004, sections 5.3–5.4).

`LandmarkModel` is the exercise-level estimator the pipeline uses: tutor-fitted signature, the
frame classifier of `analysis.landmarks.detector`, refining, and (ours) grammar typing and
relocation; `LandmarkOptions()` is our best configuration on UI-PRMD, `FAITHFUL` the thesis's
C4.5 + AdaBoost + EM + μ1.

    model = LandmarkModel().fit(tutor_motion, tutor_frames, tutor_types, training=[...])
    result = model.detect(motion)            # LandmarkResult; result.landmarks → periodic.clean
    reps = landmark_repetitions(model, motion).repetitions   # detect → GA^K → repetitions

`landmark_repetitions` is the entry point for segmentation by key poses: repetitions (start,
end-of-range frames, end, complete) from key poses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import numpy.typing as npt
from sklearn.base import BaseEstimator

from analysis.bvh import Motion
from analysis.kinematics import Kinematics, kinematics
from analysis.landmarks.detector import ClassifierName, LandmarkDetector
from analysis.landmarks.key_poses import KeyPoses
from analysis.landmarks.refining import RefineOptions, mean_poses, refine
from analysis.landmarks.regularise import (
    GrammarOptions,
    farthest_types,
    pose_distances,
    regularise,
    relocate,
    transitions,
    typical_gaps,
)
from analysis.landmarks.repetitions import Repetition, repetitions
from analysis.landmarks.signature import (
    MotionSignature,
    SignatureOptions,
    augmented_copies,
    pose_series,
)
from analysis.periodic import clean

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


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
class Identified:
    """The classifier's candidate landmarks (eq 5.23) of one performance, with its signature
    (F, k) and whether it was read mirrored (left↔right)."""

    candidates: KeyPoses
    signature: FloatArray
    mirrored: bool


@dataclass(frozen=True)
class LandmarkResult:
    """Landmarks of one performance at each stage: ``candidates`` (identification, eq 5.23),
    ``refined`` (clustering + selection, eq 5.27), ``landmarks`` (after grammar typing and
    relocation: what periodic sequence analysis receives), ``signature`` (F, k), ``mirrored``,
    ``regularised`` (after grammar typing only)."""

    candidates: KeyPoses
    refined: KeyPoses
    landmarks: KeyPoses
    signature: FloatArray
    mirrored: bool
    # after grammar typing, before relocation (same landmarks as ``landmarks``, index by index)
    regularised: KeyPoses | None = None


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
    [1, 2] for 1, 2, 1, 2, …, 1 (the order `analysis.landmarks.repetitions` expects)."""
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
        self, labelled: Sequence[Labelled], kins: Sequence[Kinematics], augment: int
    ) -> list[tuple[FloatArray, IntArray, IntArray]]:
        sig = self.signature_
        out = [
            (sig.transform(m, kin), np.asarray(f, np.int64), np.asarray(t, np.int64))
            for (m, f, t), kin in zip(labelled, kins, strict=True)
        ]
        if augment:
            tutor, frames, types = labelled[0]
            copies = augmented_copies(
                sig.smoothed(tutor, False, kins[0]), frames, types, augment, self.options.seed
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
        kins = [kinematics(m) for m, _, _ in labelled]  # one pass per recording for every use
        self.signature_ = MotionSignature(options=self.options.signature).fit(tutor, kin=kins[0])
        augment = 0 if training else self.options.augment
        samples = self._samples(labelled, kins, augment)
        self.detector_ = _detector(self.options).fit(*zip(*samples, strict=True))
        self.means_ = mean_poses(samples[0][0], frames, types)
        self.cycle_ = tutor_cycle(types)
        self.patterns_ = [[*self.cycle_, self.cycle_[0]]]
        n_types = max(int(np.max(t)) for _, _, t in labelled)
        self.allowed_ = transitions([t for _, _, t in labelled], n_types)
        self.gaps_ = typical_gaps([(f, t) for _, f, t in labelled], n_types)
        self.extreme_types_ = set()
        if self.options.relocate:
            poses = [
                (pose_series(m, kin=kin), np.asarray(f), np.asarray(t))
                for (m, f, t), kin in zip(labelled, kins, strict=True)
            ]
            self.extreme_types_ = farthest_types(poses)
        return self

    def detect(self, motion: Motion, kin: Kinematics | None = None) -> LandmarkResult:
        """Candidate, refined and final landmarks of one performance (same fps as the tutor);
        ``kin``: the motion's `kinematics` when already computed."""
        kin = kinematics(motion) if kin is None else kin
        data = self.signature_.read(motion, kin)
        names = motion.skeleton.names
        if not self.signature_.options.mirror:
            return self._detect_side(motion, kin, data, False)
        if self.options.side == "landmarks":
            sides = [self._detect_side(motion, kin, data, m) for m in (False, True)]
            return min(sides, key=self._misfit)
        return self._detect_side(motion, kin, data, self.signature_.mirrored_data(data, names))

    def identify(self, motion: Motion, kin: Kinematics | None = None) -> Identified:
        """Section 5.4 alone: the signature and the classifier's candidate landmarks (the side
        is chosen by the tutor eigenspace's variance, as `detect` does by default)."""
        signature = self.signature_
        data = signature.read(motion, kin)
        smoothed, mirrored = signature.chosen_side(data, motion.skeleton.names)
        sig = signature.project(smoothed)
        return Identified(self.detector_.candidates(sig), sig, mirrored)

    def refine_identified(
        self, identified: Identified, motion: Motion, kin: Kinematics | None = None
    ) -> LandmarkResult:
        """Section 5.5 and our grammar typing and relocation on `identify`'s candidates."""
        sig, candidates = identified.signature, identified.candidates
        refined = refine(candidates, sig, self.means_, self.options.refine)
        final = refined
        if self.options.grammar is not None:
            final = regularise(
                final, sig, self.means_, self.allowed_, self.options.grammar, gaps=self.gaps_
            )
        regularised = final
        if self.extreme_types_:
            final = relocate(final, pose_series(motion, kin=kin), self.extreme_types_)
        return LandmarkResult(candidates, refined, final, sig, identified.mirrored, regularised)

    def _misfit(self, result: LandmarkResult) -> float:
        """Mean distance of the final landmarks to their types' tutor mean signatures (inf if
        none): how well a side's key poses look like the tutor's."""
        found = result.landmarks
        if found.frames.size == 0:
            return float("inf")
        width = int(max(self.means_)) + 1
        distances = pose_distances(result.signature, self.means_, width)
        return float(np.mean(distances[found.frames, found.types]))

    def _detect_side(
        self, motion: Motion, kin: Kinematics, data: FloatArray, mirrored: bool
    ) -> LandmarkResult:
        signature = self.signature_
        sig = signature.project(signature.smoothed_data(data, motion.skeleton.names, mirrored))
        identified = Identified(self.detector_.candidates(sig), sig, bool(mirrored))
        return self.refine_identified(identified, motion, kin)


def periodic_landmarks(
    landmarks: KeyPoses, patterns: Sequence[Sequence[int]], method: str = "ga-k", seed: int = 0
) -> KeyPoses:
    """Chapter 6 on detected landmarks: keep the members `analysis.periodic.clean` keeps.

    patterns: training periods (``LandmarkModel.patterns_``, e.g. [[1, 2, 1]]); method: one of
    `analysis.periodic.sequence.METHODS` (GA^K by default). Returns the kept landmarks, in time
    order.
    """
    if landmarks.frames.size == 0:
        return landmarks
    kept = np.asarray(
        clean([int(t) for t in landmarks.types], patterns, method=method, seed=seed), np.int64
    )
    return KeyPoses(landmarks.frames[kept], landmarks.types[kept])


@dataclass(frozen=True)
class RepetitionResult:
    """Everything `landmark_repetitions` found in one performance: the detection stages
    (``detection``), the landmarks after periodic analysis (``landmarks``) and the repetitions
    (`analysis.landmarks.repetitions.Repetition`: start, end-of-range frames, end, complete,
    cycle)."""

    detection: LandmarkResult
    landmarks: KeyPoses
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
    ``method`` is None), then `analysis.landmarks.repetitions.repetitions` with the tutor's cycle.

    model: a fitted `LandmarkModel` of the exercise; motion: the performance (the tutor's fps).
    order: the cycles of `analysis.landmarks.repetitions` (default ``model.cycle_``, e.g. [1, 2]);
    give one
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
