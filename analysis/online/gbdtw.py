"""Gesture-Based DTW (paper 001, Wei et al. 2015): cut a user stream into the tutor's gestures as it
arrives, score each gesture 0-100 and say what went wrong.

For tutor gesture A_g (m_g frames) and the user stream from frame u, S(k) is the DTW cost of A_g
against user frames u..u+k (computed one user frame at a time, O(m_g) per frame). A local minimum
S(k+1) > S(k) is the gesture's end when the next e frames behave as if they all matched A_g's last
frame: with S'(k+j) = S'(k+j-1) + d(a_last, b_{u+k+j}) (eq 10) and error = |S' - S| / S (eq 11),
mean(error) < delta (e = 20, delta = 5 %). The next gesture restarts DTW at the following cell.
If the stream ends first, the smallest S seen so far wins (subsequence DTW, eq 9).

Also here: the start-point alignment of eq 6, scores from the DTW distance (eq 8, or eq 17 when
speed does not matter), the four guidance types of Table 1, the Bayes pass/fail threshold
(eqs 13-15) and the maximum cross-correlation baseline (eqs 1-2).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt
from scipy import signal

from analysis.dtw import (
    DTWOptions,
    align,
    as_frames,
    cost_matrix,
    is_quaternion_kind,
    paired_costs,
    path_groups,
    speed_insensitive_cost,
)
from analysis.online.aligners import OpenEndAligner

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
GUIDANCE = {1: "too fast", 2: "too slow", 3: "overdone", 4: "incomplete"}


@dataclass(frozen=True)
class GBDTWOptions:
    """e (``confirm_frames``) and delta (``relative_error``) of eq 11; score and guidance settings.

    score_scale: mean local cost (cost units per path cell) that scores 100/e ~ 37; scores are
    100 exp(-mean cost / score_scale). align_start: shift the user stream so that its first frame
    equals the tutor's (eq 6; Euclidean costs only). Guidance: runs shorter than ``min_run``
    frames are ignored; a type is reported when its runs cover ``guidance_share`` of the gesture.
    """

    confirm_frames: int = 20
    relative_error: float = 0.05
    dtw: DTWOptions = field(default_factory=DTWOptions)
    score_scale: float = 1.0
    align_start: bool = False
    min_run: int = 2
    guidance_share: float = 0.1
    monotonic_tol: float = 0.0


@dataclass(frozen=True)
class Run:
    """A many-to-one stretch of a gesture's path (Table 1)."""

    type: int  # 1 too fast, 2 too slow, 3 overdone, 4 incomplete
    tutor: tuple[int, int]  # first, last tutor frame
    user: tuple[int, int]  # first, last user frame


@dataclass(frozen=True, eq=False)
class Gesture:
    """One segmented gesture: user frames start..end (inclusive) matched to a tutor gesture."""

    index: int
    start: int
    end: int
    tutor_start: int
    tutor_end: int
    cost: float
    score: float
    path: IntArray = field(repr=False)  # (K, 2) absolute (tutor frame, user frame) pairs
    runs: tuple[Run, ...] = field(repr=False)
    guidance: tuple[str, ...]


@dataclass(frozen=True, eq=False)
class GBDTWResult:
    """All gestures found in the stream and the number of DP cells computed (the cost, eq 12)."""

    gestures: tuple[Gesture, ...]
    cells: int

    @property
    def path(self) -> IntArray:
        """All gestures' paths joined: (K, 2) (tutor frame, user frame)."""
        return np.concatenate([g.path for g in self.gestures])


def score(mean_cost: float, scale: float) -> float:
    """Score 0-100 from a mean local cost: 100 exp(-mean_cost / scale)."""
    return float(100.0 * math.exp(-mean_cost / scale))


def _find_end(A: FloatArray, B: FloatArray, opt: GBDTWOptions) -> tuple[int, int]:
    """End of gesture A in B (relative frame index) by the local-minimum test; cells computed."""
    oa = OpenEndAligner(A, replace(opt.dtw, open_end=False), keep_path=False)
    last = cost_matrix(A[-1:], B, opt.dtw.cost, opt.dtw.weights)[0]  # d(a_last, b_k)
    S: list[float] = []
    e, candidate = opt.confirm_frames, None
    for k in range(len(B)):
        oa.push(B[k])
        S.append(float(oa.row()[-1]))
        if candidate is None and k >= 1 and S[k] > S[k - 1]:
            candidate = k - 1
        if candidate is not None and k == candidate + e:
            if _confirmed(np.array(S), last, candidate, e, opt.relative_error):
                return candidate, (k + 1) * len(A)
            candidate = next((c for c in range(candidate + 1, k) if S[c + 1] > S[c]), None)
    return int(np.argmin(S)), len(B) * len(A)


def _confirmed(S: FloatArray, last: FloatArray, k: int, e: int, delta: float) -> bool:
    """Eqs 10-11: do the e frames after k cost what they would all matched to A's last frame?"""
    true = S[k + 1 : k + e + 1]
    est = S[k] + np.cumsum(last[k + 1 : k + e + 1])
    err = np.abs(est - true) / np.maximum(true, 1e-300)
    return bool(err.mean() < delta)


def _monotonic(frames: FloatArray, tol: float) -> bool:
    """Every feature keeps increasing or keeps decreasing over the frames (|steps| <= tol: flat)."""
    d = np.diff(frames, axis=0)
    return bool(np.all(np.all(d >= -tol, axis=0) | np.all(d <= tol, axis=0)))


def guidance_runs(
    tutor: FloatArray, user: FloatArray, path: IntArray, opt: GBDTWOptions
) -> list[Run]:
    """Table 1 types for every many-to-one run of a (tutor, user) path with >= min_run frames."""
    runs = []
    for s, e in path_groups(path):
        i, j = path[s:e, 0], path[s:e, 1]
        if e - s < opt.min_run:
            continue
        if i[0] != i[-1]:  # several tutor frames on one user frame
            kind = 1 if _monotonic(tutor[i], opt.monotonic_tol) else 4
        else:  # one tutor frame, several user frames
            kind = 2 if _monotonic(user[j], opt.monotonic_tol) else 3
        runs.append(Run(kind, (int(i[0]), int(i[-1])), (int(j[0]), int(j[-1]))))
    return runs


def _summarise(runs: list[Run], n_tutor: int, n_user: int, opt: GBDTWOptions) -> tuple[str, ...]:
    cover = dict.fromkeys(GUIDANCE, 0)
    for r in runs:
        many = r.tutor[1] - r.tutor[0] if r.type in (1, 4) else r.user[1] - r.user[0]
        cover[r.type] += many + 1
    skip = {1, 2} if opt.dtw.speed_insensitive else set()
    share = {t: cover[t] / (n_tutor if t in (1, 4) else n_user) for t in GUIDANCE}
    return tuple(GUIDANCE[t] for t in GUIDANCE if t not in skip and share[t] >= opt.guidance_share)


def _gesture(
    A: FloatArray,
    B: FloatArray,
    Bshift: FloatArray,
    *,
    index: int,
    a0: int,
    u0: int,
    opt: GBDTWOptions,
) -> Gesture:
    """Align tutor gesture A (frames a0..) with user frames u0.. (eq 7: path from the shifted
    frames, eq 8: cost from the original ones) and score it."""
    d = replace(opt.dtw, open_begin=False, open_end=False, return_matrix=False)
    path = np.array(align(A, Bshift, d).path)
    if opt.dtw.speed_insensitive:
        cost = speed_insensitive_cost(A, B, path, d.cost, d.weights)
    else:
        cost = float(paired_costs(A[path[:, 0]], B[path[:, 1]], d.cost, d.weights).sum())
    runs = guidance_runs(A, B, path, opt)
    shifted = [
        Run(r.type, (r.tutor[0] + a0, r.tutor[1] + a0), (r.user[0] + u0, r.user[1] + u0))
        for r in runs
    ]
    return Gesture(
        index=index,
        start=u0,
        end=u0 + len(B) - 1,
        tutor_start=a0,
        tutor_end=a0 + len(A) - 1,
        cost=cost,
        score=score(cost / len(path), opt.score_scale),
        path=path + np.array([a0, u0]),
        runs=tuple(shifted),
        guidance=_summarise(runs, len(A), len(B), opt),
    )


def segment(
    tutor: npt.ArrayLike,
    gestures: Sequence[tuple[int, int]],
    stream: npt.ArrayLike,
    options: GBDTWOptions | None = None,
) -> GBDTWResult:
    """Segment a user stream (n, d) into the tutor's (m, d) gestures, given as inclusive
    (first, last) tutor frames in order; stops early if the stream runs out."""
    opt = options or GBDTWOptions()
    T, U = as_frames(tutor, "tutor"), as_frames(stream, "stream")
    found, u0, cells = [], 0, 0
    for g, (a0, a1) in enumerate(gestures):
        if u0 >= len(U):
            break
        A, B = T[a0 : a1 + 1], U[u0:]
        Bs = B + (A[0] - B[0]) if opt.align_start and not is_quaternion_kind(opt.dtw.cost) else B
        k, c = _find_end(A, Bs, opt)
        cells += c
        found.append(_gesture(A, B[: k + 1], Bs[: k + 1], index=g, a0=a0, u0=u0, opt=opt))
        u0 += k + 1
    return GBDTWResult(gestures=tuple(found), cells=cells)


class BayesThreshold:
    """Pass/fail threshold on scores from therapist labels (001 eqs 13-15), Gaussian classes.

    Solves (s - mu0)^2/s0^2 - (s - mu1)^2/s1^2 + log(s0^2/s1^2) - 2 log(P0/P1) = 0, the equality
    P(s|pass) P(pass) = P(s|fail) P(fail). (Eq 15 as printed has log(2 pi s0^2/s1^2): the 2 pi
    cancels between the two densities, so it is left out.) The root between the class means is
    used. ``predict`` says True (fail, give guidance) below the threshold when passes score higher.
    """

    def __init__(self, *, priors: tuple[float, float] | None = None) -> None:
        self.priors = priors

    def fit(self, scores: npt.ArrayLike, failed: npt.ArrayLike) -> BayesThreshold:
        """scores (N,), failed (N,) bool (True = the therapist failed the gesture)."""
        s, y = np.asarray(scores, float), np.asarray(failed, bool)
        if y.all() or not y.any() or min(y.sum(), (~y).sum()) < 2:
            raise ValueError("need at least two passed and two failed scores")
        self.means_ = np.array([s[~y].mean(), s[y].mean()])
        self.stds_ = np.array([s[~y].std(ddof=1), s[y].std(ddof=1)])
        p = self.priors or ((~y).mean(), y.mean())
        self.priors_ = np.array(p, dtype=float)
        self.threshold_ = _gaussian_boundary(self.means_, self.stds_, self.priors_)
        return self

    def predict(self, scores: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """True where a score falls on the fail side of the threshold."""
        s = np.asarray(scores, float)
        below = self.means_[1] < self.means_[0]
        return s < self.threshold_ if below else s > self.threshold_


def _gaussian_boundary(mu: FloatArray, sd: FloatArray, prior: FloatArray) -> float:
    v0, v1 = sd**2
    a = 1.0 / v0 - 1.0 / v1
    b = -2.0 * mu[0] / v0 + 2.0 * mu[1] / v1
    c = mu[0] ** 2 / v0 - mu[1] ** 2 / v1 + math.log(v0 / v1) - 2.0 * math.log(prior[0] / prior[1])
    roots = [-c / b] if abs(a) < 1e-12 * max(abs(b), 1e-300) else np.roots([a, b, c])
    real = [float(np.real(r)) for r in roots if abs(np.imag(r)) < 1e-9]
    if not real:  # one class dominates everywhere: fall back to the midpoint
        return float(mu.mean())
    lo, hi = sorted(mu)
    inside = [r for r in real if lo <= r <= hi]
    return inside[0] if inside else min(real, key=lambda r: abs(r - mu.mean()))


def cross_correlation_shift(f: npt.ArrayLike, g: npt.ArrayLike, demean: bool = True) -> int:
    """Eqs 1-2: tau = argmax_n sum_m f(m) g(m + n), summed over features; f (n, d), g (m, d).

    ``demean`` removes each feature's mean first: for non-negative signals the raw sum is largest
    at the shift with the most overlap, not at the matching shape.
    """
    F, G = as_frames(f, "f"), as_frames(g, "g")
    if demean:
        F, G = F - F.mean(axis=0), G - G.mean(axis=0)
    R = sum(signal.correlate(G[:, k], F[:, k], mode="full") for k in range(F.shape[1]))
    lags = signal.correlation_lags(len(G), len(F), mode="full")
    return int(lags[int(np.argmax(R))])


def shift_path(n_f: int, n_g: int, tau: int) -> IntArray:
    """The alignment a shift tau makes: pairs (m, m + tau) inside both sequences, (K, 2)."""
    m = np.arange(max(0, -tau), min(n_f, n_g - tau))
    return np.stack([m, m + tau], axis=1).astype(np.int64)
