"""Joint weights for (Open-End) DTW optimised by CMA-ES on labelled recordings (paper 000, 4.2).

The objective is eq 5: the share of frames aligned to the wrong movement segment, averaged over
the training recordings. A recording's frames are aligned either on-line (each frame t to the
open-end answer after frames 0..t, what a streaming aligner shows) or along the final warping path.
CMA-ES as in the paper: initial w = 1, step size 0.02, 6 parents and 12 offspring per generation,
``iterations`` generations (300 in the paper). Negative samples are folded to |w|; the result is
scaled to mean 1 (DTW decisions do not change with a common factor).

One fitness evaluation is, per recording, a compiled weighted cost matrix and one compiled DP pass;
the offspring of a generation are scored in parallel threads.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from types import ModuleType
from typing import TYPE_CHECKING, Literal

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.dtw.frame_costs import as_frames, cost_matrix, n_joints
from analysis.dtw.joint_terms import JointTerms
from analysis.dtw.offline import DPState, DTWOptions, band_limits

if TYPE_CHECKING:
    import cma

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
Target = Literal["online", "path"]


def _cma() -> ModuleType:
    """The cma library, imported when weights are fitted: importing it loads matplotlib's
    plotting (0.8 s on the project's VM), which every web, worker and command-line process would
    otherwise pay for at start. (A third-party library, not a project module: no cycle.)"""
    with warnings.catch_warnings():  # cma warns when matplotlib (plots only) is missing
        warnings.simplefilter("ignore")
        import cma

    return cma


def aligned_pairs(C: FloatArray, options: DTWOptions, target: Target = "online") -> IntArray:
    """Frame pairs (K, 2) that open-end DTW on local costs C (n, m) produces.

    "online": (t, Omega_t) for every t, Omega_t the open-end answer after frames 0..t.
    "path": the warping path back from the last frame's open-end answer.
    """
    n, m = C.shape
    opt = replace(options, open_end=True, return_matrix=False)
    lo, hi = band_limits(n, m, opt)
    state = DPState(n, m, opt, path=target == "path", omega=True)
    state.rows(C, 0, n, lo, hi)
    if target == "online":
        return np.stack([np.arange(n), np.maximum(state.omega, 0)], axis=1)
    return state.backtrack(n - 1, int(state.omega[n - 1]))


def alignment_error(
    pairs: IntArray, labels: npt.ArrayLike, reference_labels: npt.ArrayLike
) -> float:
    """Eq 5: #IA / (#CA + #IA), the share of pairs whose segment labels differ."""
    lx, ly = np.asarray(labels), np.asarray(reference_labels)
    return float(np.mean(lx[pairs[:, 0]] != ly[pairs[:, 1]]))


class JointWeightOptimizer:
    """CMA-ES joint weights (sklearn style): ``fit(...)`` sets ``weights_`` (J,), ``error_``.

    options: the DTW the weights are for (cost kind, path-length weighting, ...); weights in it
    are ignored. iterations: CMA-ES generations. target: "online" or "path" (see
    ``aligned_pairs``). joints: number of weight groups for Euclidean costs (the features of a
    frame split evenly; default one per feature; quaternion costs always use one per quaternion).
    n_threads: offspring scored in parallel (default: numba's threads).
    """

    def __init__(
        self,
        *,
        options: DTWOptions | None = None,
        iterations: int = 300,
        sigma0: float = 0.02,
        parents: int = 6,
        offspring: int = 12,
        target: Target = "online",
        seed: int = 0,
        joints: int | None = None,
        n_threads: int | None = None,
    ) -> None:
        self.options = options or DTWOptions(cost="quaternion", path_length_weighting=True)
        self.iterations = iterations
        self.sigma0 = sigma0
        self.parents = parents
        self.offspring = offspring
        self.target = target
        self.seed = seed
        self.joints = joints
        self.n_threads = n_threads or nb.get_num_threads()

    def _error(
        self,
        w: FloatArray,
        frames: list[FloatArray],
        ref: FloatArray,
        labels: list[IntArray],
        ref_labels: IntArray,
        *,
        terms: Sequence[JointTerms] = (),
    ) -> float:
        """Eq 5 averaged over the recordings, for joint weights w; ``terms``: the recordings'
        per-joint quaternion terms (`analysis.dtw.joint_terms`), when the cost is quaternion."""
        opt = replace(self.options, weights=None)
        errors = []
        for k, (x, lab) in enumerate(zip(frames, labels, strict=True)):
            C = terms[k].costs(w) if terms else cost_matrix(x, ref, opt.cost, w)
            errors.append(alignment_error(aligned_pairs(C, opt, self.target), lab, ref_labels))
        return float(np.mean(errors))

    def _strategy(self, joints: int) -> cma.CMAEvolutionStrategy:
        """CMA-ES as in paper 000: start at w = 1 with step 0.02, mu = 6 of lambda = 12.

        The fitness is piecewise constant (a share of frames), so the flat-fitness and stagnation
        stops are pushed out to the iteration budget."""
        options = {
            "popsize": self.offspring, "CMA_mu": self.parents, "seed": self.seed + 1,
            "maxiter": self.iterations, "verbose": -9, "tolfun": 0, "tolfunhist": 0, "tolx": 0,
            "tolflatfitness": self.iterations, "tolstagnation": self.iterations,
        }  # fmt: skip
        return _cma().CMAEvolutionStrategy(np.ones(joints), self.sigma0, options)

    def fit(
        self,
        reference: npt.ArrayLike,
        reference_labels: npt.ArrayLike,
        recordings: Sequence[npt.ArrayLike],
        labels: Sequence[npt.ArrayLike],
    ) -> JointWeightOptimizer:
        """reference (m, d) with segment labels (m,); recordings (n_k, d) with labels (n_k,)."""
        ref = as_frames(reference, "reference")
        frames = [as_frames(r, "recording") for r in recordings]
        lab, ref_lab = [np.asarray(x) for x in labels], np.asarray(reference_labels)
        groups = None if self.joints is None else np.ones(self.joints)
        J = n_joints(ref.shape[1], self.options.cost, groups)

        # only the weights change between evaluations: each joint's quaternion terms once
        quaternion = self.options.cost == "quaternion"
        terms = [JointTerms(x, ref) for x in frames] if quaternion else []

        def error(w: FloatArray) -> float:
            return self._error(np.abs(w), frames, ref, lab, ref_lab, terms=terms)

        self.initial_error_ = error(np.ones(J))
        es = self._strategy(J)
        best_w, best_f, self.history_ = np.ones(J), self.initial_error_, []
        # the compiled cost and DP kernels release the GIL: offspring are scored on all cores
        with ThreadPoolExecutor(max_workers=self.n_threads) as pool:
            while not es.stop():
                X = es.ask()
                f = list(pool.map(error, X))
                es.tell(X, f)
                k = int(np.argmin(f))
                if f[k] < best_f:
                    best_w, best_f = np.abs(X[k]), f[k]
                self.history_.append(best_f)
        self.weights_ = best_w / best_w.mean() if best_w.mean() > 0 else np.ones(J)
        self.error_ = best_f
        return self
