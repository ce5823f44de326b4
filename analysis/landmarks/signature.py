"""Motion signature (paper 004, section 5.2): smoothing, joint selection and the tutor's PCA.

The signature of a performance is a few standardised principal-component series of the smoothed
motion data of the exercise's involved joints, with the loadings and means learnt from the *tutor*
(eq 5.5): the same eigenspace is used for every performance of the exercise, so that the tutor's
mean signature per landmark type (eq 5.30) is comparable with any performance's signature.

Data sources: ``"positions"`` (root-relative positions facing a common heading, cm) or
``"quaternions"`` (local joint rotations, made sign-continuous and put in the tutor's hemisphere).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt
from scipy.interpolate import CubicSpline
from sklearn.base import BaseEstimator, TransformerMixin

from analysis.bvh import Motion
from analysis.kinematics import Kinematics, kinematics
from analysis.kinematics import quaternions as quat

FloatArray = npt.NDArray[np.float64]
Source = Literal["positions", "quaternions"]
Scaling = Literal["tutor", "self", "none"]


@dataclass(frozen=True)
class SignatureOptions:
    """Parameters of the motion signature.

    source: motion data source M^P; window: resampling window ω in seconds (eq 5.1, 0.4–0.5 in
    Table 5.1); variance: cumulative level of representation kept (eq 5.8); joints: involved joint
    names, or None for the ``n_joints`` joints that move most in the tutor; scaling: standardise the
    PCs with the tutor's standard deviations ("tutor"), with the performance's own mean and standard
    deviation ("self"), or not at all ("none"); mirror (ours): also try the performance reflected
    left↔right and keep the side the tutor's eigenspace explains better, for patients who use the
    other limb or start with the other side.
    """

    source: Source = "positions"
    window: float = 0.4
    variance: float = 0.9
    joints: tuple[str, ...] | None = None
    n_joints: int = 4
    scaling: Scaling = "self"
    mirror: bool = False


def smooth(data: FloatArray, window_frames: float) -> FloatArray:
    """Eq 5.1: resample every column at one knot per window and fit a cubic spline back.

    data: (F, D); window_frames: ω in frames (> 0). Each knot holds the mean of the frames within
    half a window of it (averaging, not picking, so that noise does not alias into the knots);
    knots are evenly spaced and include the first and last frame. Returns (F, D).
    """
    data = np.asarray(data, dtype=np.float64)
    n = data.shape[0]
    n_knots = round((n - 1) / window_frames) + 1 if n > 1 else 1
    if n_knots < 4:
        return data.copy()
    knots = np.linspace(0.0, n - 1.0, n_knots)
    half = 0.5 * window_frames
    lo = np.clip(np.ceil(knots - half), 0, n - 1).astype(np.int64)
    hi = np.clip(np.floor(knots + half), 0, n - 1).astype(np.int64) + 1
    cumulative = np.vstack([np.zeros((1, data.shape[1])), np.cumsum(data, axis=0)])
    means = (cumulative[hi] - cumulative[lo]) / (hi - lo)[:, None]
    return np.asarray(CubicSpline(knots, means, axis=0)(np.arange(n, dtype=np.float64)))


def mirror_index(names: tuple[str, ...]) -> npt.NDArray[np.int64]:
    """Each joint's left/right counterpart (by a Left↔Right swap in its name), or itself."""
    swapped = [
        n.replace("Left", "\0").replace("Right", "Left").replace("\0", "Right") for n in names
    ]
    return np.array([names.index(n) if n in names else k for k, n in enumerate(swapped)])


def motion_data(motion: Motion, source: Source, kin: Kinematics | None = None) -> FloatArray:
    """The motion data of one source before any mirroring: (F, J, 3) root-relative positions
    facing a common heading (cm, `Kinematics.facing`: read-only) or (F, J, 4) local rotations
    without sign jumps in time. ``kin``: the motion's `kinematics` when already computed (a
    pipeline run passes its own)."""
    kin = kinematics(motion) if kin is None else kin
    if source == "positions":
        return kin.facing
    q = kin.local_q.copy()
    q[0] = quat.canonical(q[0])
    return quat.make_continuous(q, axis=0)


def oriented(
    data: FloatArray,
    names: tuple[str, ...],
    reference: FloatArray | None = None,
    mirror: bool = False,
    joints: Sequence[int] | None = None,
) -> FloatArray:
    """`motion_data` (positions or quaternions, told apart by the last axis) reflected left↔right
    when ``mirror`` and, for quaternions, put in ``reference``'s hemisphere; ``joints``: only
    these joints' series (F, len(joints), k), in that order (each joint's values are those it has
    among all joints: a joint's orientation depends on that joint alone)."""
    quaternions = data.shape[-1] == 4
    chosen = np.arange(data.shape[1]) if joints is None else np.asarray(joints, dtype=np.int64)
    if mirror:
        flip_axes = [1.0, 1.0, -1.0, -1.0] if quaternions else [-1.0, 1.0, 1.0]
        data = data[:, mirror_index(names)[chosen]] * flip_axes
    elif joints is not None:
        data = data[:, chosen]
    if quaternions and reference is not None:
        data = data if mirror or joints is not None else data.copy()  # else already a new array
        flip = np.sum(data.mean(axis=0) * reference[chosen], axis=-1) < 0.0
        data[:, flip] *= -1.0
    return data


def joint_series(
    motion: Motion,
    source: Source,
    reference: FloatArray | None = None,
    mirror: bool = False,
    kin: Kinematics | None = None,
) -> FloatArray:
    """Per-joint motion data of one source: (F, J, 3) positions in cm or (F, J, 4) quaternions.

    reference: (J, 4) quaternions whose hemisphere each joint's rotations are put in (quaternions
    only), so that q and -q of the same pose give the same signature for tutor and performance.
    mirror: the performance reflected left↔right (x is lateral after heading normalisation): left
    and right joints swap, x positions change sign, rotations (w, x, y, z) become (w, x, −y, −z).
    """
    return oriented(motion_data(motion, source, kin), motion.skeleton.names, reference, mirror)


def moving_joints(series: FloatArray, n_joints: int) -> tuple[int, ...]:
    """Indices of the ``n_joints`` joints with the largest total variance over time, in file order.

    series: (F, J, k) per-joint data (e.g. from `joint_series`). Joints that never move (the root of
    root-relative positions) are never chosen.
    """
    amount = np.var(series, axis=0).sum(axis=-1)
    order = np.argsort(-amount, kind="stable")
    chosen = [int(j) for j in order[:n_joints] if amount[j] > 1e-12]
    return tuple(sorted(chosen))


def n_components_for(explained: FloatArray, variance: float) -> int:
    """Eq 5.8: the smallest Δ_k whose cumulative representation ρ (eq 5.6) reaches ``variance``.

    explained: (p,) eigenvalues e_l (any order is sorted descending first).
    """
    e = np.sort(np.asarray(explained, dtype=np.float64))[::-1]
    rho = np.cumsum(e) / max(float(e.sum()), 1e-300)
    return min(int(np.searchsorted(rho, variance - 1e-12)) + 1, int(e.size))


def pca_loadings(data: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Eqs 5.2–5.4 by SVD of the centred data: (means (p,), loadings W (p, p), eigenvalues (p,))."""
    means = data.mean(axis=0)
    _, singular, wt = np.linalg.svd(data - means, full_matrices=False)
    eigen = singular**2 / max(data.shape[0] - 1, 1)
    # Fix each loading's sign (largest coefficient positive) so refits give the same signature.
    signs = np.where(wt[np.arange(wt.shape[0]), np.argmax(np.abs(wt), axis=1)] < 0, -1.0, 1.0)
    return means, (wt * signs[:, None]).T, eigen


class MotionSignature(TransformerMixin, BaseEstimator):
    """Tutor-fitted PCA signature (eqs 5.5–5.8) of any performance of the same exercise.

    Learnt: ``joints_`` (indices), ``means_`` (p,), ``loadings_`` (p, Δ_k), ``explained_`` (p,),
    ``scale_`` (Δ_k,), ``reference_`` (J, 4) or None, ``window_frames_`` (ω in tutor frames).
    """

    def __init__(self, *, options: SignatureOptions = SignatureOptions()) -> None:
        self.options = options

    def read(self, motion: Motion, kin: Kinematics | None = None) -> FloatArray:
        """The options' source of motion data (`motion_data`), read once per performance."""
        return motion_data(motion, self.options.source, kin)

    def smoothed(
        self, motion: Motion, mirror: bool | None = None, kin: Kinematics | None = None
    ) -> FloatArray:
        """The smoothed motion data C of the involved joints (eq 5.1): (F, p).

        mirror: None = the side `mirrored` chooses when the options allow mirroring, else as given.
        """
        return self.smoothed_data(self.read(motion, kin), motion.skeleton.names, mirror)

    def smoothed_data(
        self, data: FloatArray, names: tuple[str, ...], mirror: bool | None = None
    ) -> FloatArray:
        """`smoothed` from already read motion data (`read`) and the performance's joint names."""
        if mirror is None:
            return self.chosen_side(data, names)[0]
        series = oriented(data, names, self.reference_, mirror, self.joints_)
        return smooth(series.reshape(data.shape[0], -1), self.window_frames_)

    def captured(self, smoothed: FloatArray) -> float:
        """Variance of the data (F, p) inside the kept eigenspace, about the data's own mean (the
        tutor's means would let body size, not movement, decide)."""
        inside = (smoothed - smoothed.mean(axis=0)) @ self.loadings_
        return float(np.mean(np.sum(inside**2, axis=1)))

    def mirrored(self, motion: Motion, kin: Kinematics | None = None) -> bool:
        """Whether the left↔right reflection of it fits the tutor's eigenspace better."""
        return self.mirrored_data(self.read(motion, kin), motion.skeleton.names)

    def mirrored_data(self, data: FloatArray, names: tuple[str, ...]) -> bool:
        """`mirrored` from already read motion data."""
        straight = self.captured(self.smoothed_data(data, names, False))
        return self.captured(self.smoothed_data(data, names, True)) > straight

    def chosen_side(self, data: FloatArray, names: tuple[str, ...]) -> tuple[FloatArray, bool]:
        """The smoothed data (`smoothed_data`) of the side the options choose, and whether it is
        the mirrored one (`mirrored_data` when the options allow mirroring): each side smoothed
        once."""
        straight = self.smoothed_data(data, names, False)
        if not self.options.mirror:
            return straight, False
        flipped = self.smoothed_data(data, names, True)
        if self.captured(flipped) > self.captured(straight):
            return flipped, True
        return straight, False

    def fit(
        self, tutor: Motion, y: object = None, kin: Kinematics | None = None
    ) -> MotionSignature:
        """Learn the joints, means and loadings from the tutor's smoothed motion data."""
        opts = self.options
        self.reference_ = None
        series = self.read(tutor, kin)
        if opts.source == "quaternions":
            self.reference_ = series.mean(axis=0)
        names = tutor.skeleton.names
        self.joints_ = (
            tuple(names.index(j) for j in opts.joints)
            if opts.joints
            else moving_joints(series, opts.n_joints)
        )
        self.window_frames_ = opts.window * tutor.fps
        data = self.smoothed_data(series, tutor.skeleton.names, False)
        self.means_, loadings, self.explained_ = pca_loadings(data)
        k = n_components_for(self.explained_, opts.variance)
        self.loadings_ = loadings[:, :k]
        self.scale_ = np.sqrt(np.maximum(self.explained_[:k], 1e-12))
        return self

    def transform(self, motion: Motion, kin: Kinematics | None = None) -> FloatArray:
        """The signature sig of a performance: (F, Δ_k) standardised PC scores."""
        return self.project(self.smoothed(motion, kin=kin))

    def project(self, smoothed: FloatArray) -> FloatArray:
        """Eq 5.5 on already smoothed data (F, p): (C − tutor means)·V_k, then standardised."""
        scores = (smoothed - self.means_) @ self.loadings_
        if self.options.scaling == "tutor":
            return np.asarray(scores / self.scale_)
        if self.options.scaling == "self":
            std = scores.std(axis=0)
            return np.asarray((scores - scores.mean(axis=0)) / np.where(std > 1e-12, std, 1.0))
        return np.asarray(scores)


def pose_series(motion: Motion, window: float = 0.15, kin: Kinematics | None = None) -> FloatArray:
    """(F, J, 3) root-relative, heading-normalised positions (cm), lightly smoothed by eq 5.1 with
    ω = ``window`` seconds: the whole-body pose used to place extreme key poses."""
    data = motion_data(motion, "positions", kin)
    flat = smooth(data.reshape(motion.n_frames, -1), window * motion.fps)
    return flat.reshape(data.shape)


def _warp_times(n: int, rng: np.random.Generator) -> FloatArray:
    """Input times (frames) of a warped copy: a smooth random tempo, overall 0.8–1.25× as long."""
    tempo = np.exp(smooth(rng.normal(0.0, 0.25, (n, 1)), 60.0)[:, 0])
    times = np.concatenate([[0.0], np.cumsum(tempo)])
    times *= (n - 1) / times[-1]
    n_out = round(n * rng.uniform(0.8, 1.25))
    return np.interp(np.linspace(0.0, n, n_out, endpoint=False), np.arange(n + 1.0), times)


def augmented_copies(
    smoothed: FloatArray,
    frames: npt.ArrayLike,
    types: npt.ArrayLike,
    copies: int,
    seed: int = 0,
) -> list[tuple[FloatArray, npt.NDArray[np.int64], npt.NDArray[np.int64]]]:
    """Warped copies of a labelled recording for a cold start (ours): a smooth random time warp,
    a range of motion reduced 0–40 % toward the pose of the first landmark type (the rest pose),
    and smoothed measurement noise. smoothed: (F, p) data C; returns [(C', frames', types')]."""
    rng = np.random.default_rng(seed)
    frames = np.asarray(frames, dtype=np.int64)
    types = np.asarray(types, dtype=np.int64)
    rest = smoothed[frames[types == types[0]]].mean(axis=0)
    scale = smoothed.std(axis=0).mean()
    out = []
    for _ in range(copies):
        times = _warp_times(smoothed.shape[0], rng)
        grid = np.arange(smoothed.shape[0], dtype=np.float64)
        copy = np.stack([np.interp(times, grid, column) for column in smoothed.T], axis=1)
        copy = rest + (copy - rest) * rng.uniform(0.6, 1.0)
        copy += smooth(rng.normal(0.0, 0.05 * scale, copy.shape), 4.0)
        moved = np.minimum(np.searchsorted(times, frames), len(times) - 1)
        keep = np.concatenate([[True], np.diff(moved) > 0])
        out.append((copy, moved[keep], types[keep]))
    return out
