"""Per-joint assessment of key poses against the tutor (paper 004, 7.2, eqs 7.4–7.13).

Public API (numpy in, numpy out; J = joints, L = landmarks; levels are 1..N_A, 1 = as the tutor):

- ``tutor_mean_poses(local_q (F, J, 4), frames, types) -> {type: (J, 4)}`` — eq 5.30 on rotations:
  the mean of the tutor's poses at its landmarks of each type, per joint the eigenvector mean of
  the quaternions (the unit q maximising Σ (q·q_i)², which ignores the sign ambiguity q ≡ −q).
- ``pose_difference_features(user_q (L, J, 4), reference_q (L, J, 4)) -> (L, J, 4)`` — eq 7.4 on
  rotations: the relative rotation reference⁻¹·user per joint as a rotation vector in degrees
  (axis × angle) and its angle in degrees (last column, ≥ 0).
- ``landmark_features(local_q, frames, types, mean_poses) -> (L, J, 4)`` — the features of the
  poses at the given landmarks against the mean pose of each landmark's type.
- ``joint_relevance(mean_poses) -> (J,) degrees`` — how far each joint moves between key poses.
- ``LandmarkAssessor`` — eqs 7.9–7.11: one sub-classifier Ψ_i per joint (C4.5-style entropy tree
  boosted with AdaBoost by default); ``fit(features, levels, types=None)``, ``predict -> (L, J)``.
- ``ThresholdAssessor`` — the calibrated rule-based fallback for exercises without labelled
  recordings: level 1 + ⌊angle / b⌋ (capped at N_A) with the base width
  b = max(k · tutor spread, floor) per landmark type and joint, the spread being the RMS angle of
  the tutor's own landmark poses about its mean pose of that type (k = 2.5, floor = 10°).

Both assessors expose ``predict(features, types=None) -> (L, J)`` ints so the pipeline treats them
alike. Level 0 means "not assessed" (a joint without any training label); levels ≤ 0 in training
data mark missing labels (eq 7.5's *none*) and are ignored for that joint.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.ensemble import AdaBoostClassifier
from sklearn.tree import DecisionTreeClassifier

from analysis.kinematics import quaternions as quat

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
N_LEVELS = 4  # N_A of the paper (Table 7.1)

__all__ = [
    "N_LEVELS",
    "LandmarkAssessor",
    "ThresholdAssessor",
    "joint_relevance",
    "landmark_features",
    "mean_quaternion",
    "pose_difference_features",
    "tutor_mean_poses",
]


def mean_quaternion(q: FloatArray, axis: int = 0) -> FloatArray:
    """Eigenvector mean of unit quaternions along ``axis``: (..., N, ..., 4) → (..., 4), w ≥ 0.

    The principal eigenvector of Σ q_i q_iᵀ (Markley et al. 2007); unlike the arithmetic mean of
    eq 5.30 it does not depend on the sign each sample happens to have.
    """
    q = np.moveaxis(np.asarray(q, dtype=np.float64), axis, -2)
    scatter = np.einsum("...ni,...nj->...ij", q, q)
    _, vectors = np.linalg.eigh(scatter)
    return quat.canonical(vectors[..., :, -1])


def tutor_mean_poses(
    local_q: FloatArray, frames: npt.ArrayLike, types: npt.ArrayLike
) -> dict[int, FloatArray]:
    """Mean local pose (J, 4) of the tutor at its landmarks of each type (eq 5.30)."""
    q = np.asarray(local_q, dtype=np.float64)
    f = np.asarray(frames, dtype=np.int64)
    t = np.asarray(types, dtype=np.int64)
    if f.shape != t.shape:
        raise ValueError("give one landmark type per landmark frame")
    return {int(k): mean_quaternion(q[f[t == k]], axis=0) for k in np.unique(t)}


def pose_difference_features(user_q: FloatArray, reference_q: FloatArray) -> FloatArray:
    """Per joint, reference⁻¹·user as a rotation vector (3, degrees) and its angle (degrees).

    (L, J, 4) × (L, J, 4) → (L, J, 4). Rotations, not Euler angles: no gimbal lock, no wrap-round.
    """
    rel = quat.multiply(quat.conjugate(reference_q), np.asarray(user_q, dtype=np.float64))
    rotvec = np.degrees(quat.to_rotvec(rel))
    return np.concatenate((rotvec, np.linalg.norm(rotvec, axis=-1, keepdims=True)), axis=-1)


def landmark_features(
    local_q: FloatArray,
    frames: npt.ArrayLike,
    types: npt.ArrayLike,
    mean_poses: Mapping[int, FloatArray],
) -> FloatArray:
    """Features (L, J, 4) of the poses at ``frames`` against the mean pose of each one's type.

    Raises KeyError naming the type when a landmark type has no mean pose.
    """
    q = np.asarray(local_q, dtype=np.float64)
    kinds = [int(t) for t in np.asarray(types, dtype=np.int64).ravel()]
    missing = sorted(set(kinds) - set(mean_poses))
    if missing:
        raise KeyError(f"no tutor mean pose for landmark type(s) {missing}")
    reference = np.stack([mean_poses[t] for t in kinds]) if kinds else q[:0]
    return pose_difference_features(q[np.asarray(frames, dtype=np.int64).ravel()], reference)


def joint_relevance(mean_poses: Mapping[int, FloatArray]) -> FloatArray:
    """Largest angle (degrees) between any two landmark types' mean poses, per joint: (J,).

    A joint that hardly changes between key poses (a few degrees) is not part of the exercise.
    """
    poses = np.stack(list(mean_poses.values()))
    pairwise = quat.angle_between(poses[:, None], poses[None, :], degrees=True)
    return np.asarray(pairwise.max(axis=(0, 1)), dtype=np.float64)


def default_estimator(random_state: int | None = 0) -> ClassifierMixin:
    """C4.5-style tree (entropy criterion, small leaves) boosted by AdaBoost (SAMME)."""
    tree = DecisionTreeClassifier(criterion="entropy", min_samples_leaf=2, max_depth=3)
    return AdaBoostClassifier(estimator=tree, n_estimators=30, random_state=random_state)


def _design(features: FloatArray, types: npt.ArrayLike | None, joint: int | None) -> FloatArray:
    """Rows for one joint's sub-classifier: its own 4 features (or all joints'), plus the type."""
    x = np.asarray(features, dtype=np.float64)
    rows = x[:, joint, :] if joint is not None else x.reshape(len(x), -1)
    if types is None:
        return rows
    return np.column_stack((rows, np.asarray(types, dtype=np.float64)))


class LandmarkAssessor(ClassifierMixin, BaseEstimator):
    """Multi-target landmark assessment Ψ = {Ψ_i} (eqs 7.9–7.11): one classifier per joint.

    Parameters: ``estimator`` — any sklearn classifier, cloned per joint (default: entropy tree +
    AdaBoost, ``default_estimator``); ``per_joint_features`` — Ψ_i sees only joint i's 4 features
    (True, the paper's reading) or every joint's; ``random_state`` for the default estimator.
    Learned: ``n_joints_``, ``uses_types_``, ``models_`` (per joint: a fitted classifier, an int
    for a joint whose labels have one class, or 0 for a joint without labels).
    """

    def __init__(
        self,
        *,
        estimator: ClassifierMixin | None = None,
        per_joint_features: bool = True,
        random_state: int | None = 0,
    ) -> None:
        self.estimator = estimator
        self.per_joint_features = per_joint_features
        self.random_state = random_state

    def fit(
        self, features: FloatArray, levels: npt.ArrayLike, types: npt.ArrayLike | None = None
    ) -> LandmarkAssessor:
        """Learn from features (L, J, 4) and therapist levels (L, J) (≤ 0 = no label)."""
        x = np.asarray(features, dtype=np.float64)
        y = np.asarray(levels, dtype=np.int64)
        if x.ndim != 3 or y.shape != x.shape[:2]:
            raise ValueError(
                f"features must be (L, J, 4) and levels (L, J); got {x.shape}, {y.shape}"
            )
        self.n_joints_ = x.shape[1]
        self.uses_types_ = types is not None
        self.models_: list[Any] = [self._fit_joint(x, y[:, j], types, j) for j in range(x.shape[1])]
        return self

    def _fit_joint(
        self, x: FloatArray, y: IntArray, types: npt.ArrayLike | None, joint: int
    ) -> Any:
        labelled = y > 0
        classes = np.unique(y[labelled])
        if classes.size <= 1:
            return int(classes[0]) if classes.size else 0
        rows = _design(x, types, joint if self.per_joint_features else None)
        base = default_estimator(self.random_state) if self.estimator is None else self.estimator
        return clone(base).fit(rows[labelled], y[labelled])

    def predict(self, features: FloatArray, types: npt.ArrayLike | None = None) -> IntArray:
        """Levels (L, J) ints in 1..N_A (0 for a joint that had no training label)."""
        x = np.asarray(features, dtype=np.float64)
        if x.ndim != 3 or x.shape[1] != self.n_joints_:
            raise ValueError(f"features must be (L, {self.n_joints_}, 4); got {x.shape}")
        if self.uses_types_ and types is None:
            raise ValueError("this assessor was trained with landmark types: pass types")
        types = types if self.uses_types_ else None
        out = np.zeros(x.shape[:2], dtype=np.int64)
        for j, model in enumerate(self.models_):
            if isinstance(model, int):
                out[:, j] = model
            elif len(x):
                rows = _design(x, types, j if self.per_joint_features else None)
                out[:, j] = model.predict(rows)
        return out


class ThresholdAssessor(BaseEstimator):
    """Rule-based assessment calibrated on the tutor's own variability (no labels needed).

    Level = 1 + ⌊angle / b⌋ capped at ``n_levels``, where angle is the joint's deviation (degrees,
    feature column 3) and b = max(``spread_factor`` · s, ``floor_deg``) is the base width for the
    landmark's type and the joint; s is the RMS deviation of the tutor's landmarks of that type
    from their mean pose. So level 1 holds what the tutor itself does from one repetition to the
    next (k = 2.5 RMS keeps ~99 % of a Gaussian spread), and each further level is one more base
    width away. The floor (10°) is about the repeatability of a goniometer or of a Kinect joint
    angle, below which a deviation is not meaningful. Learned: ``types_`` (T,), ``base_`` (T, J)
    and ``pooled_base_`` (J,) degrees (used for a type the tutor did not have, or no types).
    """

    def __init__(
        self, *, n_levels: int = N_LEVELS, spread_factor: float = 2.5, floor_deg: float = 10.0
    ) -> None:
        self.n_levels = n_levels
        self.spread_factor = spread_factor
        self.floor_deg = floor_deg

    def _base(self, angles: FloatArray) -> FloatArray:
        spread = np.sqrt(np.mean(angles**2, axis=0)) if len(angles) else np.zeros(angles.shape[1])
        return np.maximum(self.spread_factor * spread, self.floor_deg)

    def fit(self, features: FloatArray, types: npt.ArrayLike | None = None) -> ThresholdAssessor:
        """Calibrate on the tutor's features (L, J, 4) against its own mean poses; types (L,)."""
        x = np.asarray(features, dtype=np.float64)
        if x.ndim != 3 or x.shape[2] != 4:
            raise ValueError(f"features must be (L, J, 4); got {x.shape}")
        if self.floor_deg <= 0:
            raise ValueError("floor_deg must be positive")
        t = np.zeros(len(x), dtype=np.int64) if types is None else np.asarray(types, np.int64)
        self.types_ = np.unique(t)
        self.base_ = np.stack([self._base(x[t == k, :, 3]) for k in self.types_])
        self.pooled_base_ = self._base(x[:, :, 3])
        return self

    def thresholds(self, landmark_type: int | None = None) -> FloatArray:
        """Upper angle bounds (J, n_levels − 1) in degrees of levels 1..n_levels − 1."""
        hit = np.flatnonzero(self.types_ == landmark_type)
        base = self.base_[hit[0]] if hit.size else self.pooled_base_
        return base[:, None] * np.arange(1, self.n_levels)

    def predict(self, features: FloatArray, types: npt.ArrayLike | None = None) -> IntArray:
        """Levels (L, J) ints in 1..n_levels from the deviation angles of features (L, J, 4)."""
        x = np.asarray(features, dtype=np.float64)
        if x.ndim != 3 or x.shape[1] != self.base_.shape[1]:
            raise ValueError(f"features must be (L, {self.base_.shape[1]}, 4); got {x.shape}")
        if types is None or not len(x):
            base = np.broadcast_to(self.pooled_base_, x.shape[:2])
        else:
            kinds = np.asarray(types, dtype=np.int64).ravel()
            base = np.stack([self.thresholds(int(k))[:, 0] for k in kinds]).reshape(x.shape[:2])
        steps = np.floor(x[:, :, 3] / base).astype(np.int64)
        return 1 + np.clip(steps, 0, self.n_levels - 1)
