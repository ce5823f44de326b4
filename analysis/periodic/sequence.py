"""Periodic landmark sequence analysis (thesis 004, chapter 6): drop the out-of-sequence members.

A sample is a list of symbols (landmark types) that should repeat training periods, e.g. the
tutor's ``[1, 2, 1]`` (start, end of range, next start). :func:`clean` returns the indices of
the members to keep::

    kept = clean([1, 2, 1, 3, 2, 1], [[1, 2, 1]], method="ga-k", seed=0)   # -> [0, 1, 2, 4, 5]

Methods: ``"naive"`` (NaivePSA, Alg 2), ``"nw*"`` (NeedlemanWunsch*, Alg 3), ``"ga"`` (GA with
MutateRandom), ``"ga-k"`` (GA with MutatePrior, "GA^K", the thesis's best), and the baselines
``"nw"`` (Needleman-Wunsch) and ``"sw"`` (Smith-Waterman), see ``periodic_align``.

``"ga"`` and ``"ga-k"`` run with :data:`TUNED_GA` / :data:`TUNED_GA_K` unless ``options`` is
given: the thesis's selection, crossover and mutation operators on our cyclic-alignment fitness
(``periodic_cost``), with elitism, and for GA^K a population seeded by a greedy MutatePrior
descent and NaivePSA. The thesis's fitness (eqs 6.21–6.24, Alg 5) and operators as printed are
:data:`PAPER_GA` / :data:`PAPER_GA_K` (``periodic_fitness``, ``periodic_ga``); on the 6.4.1
benchmark they reach 0.69–0.86 accuracy, ours 0.96–0.98 (docs/sections/eval_periodic.md).
Everything is deterministic for a given ``seed``.

Modules: ``periodic_fitness`` (periods, eqs 6.14–6.24, Alg 5, integer coding, kernels),
``periodic_cost`` (our fitness), ``periodic_align`` (NW, SW, NW*), ``periodic_ga`` (Algs 4–7),
``periodic_bench`` (the random periodic benchmark and metrics, eqs 6.38–6.39).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from analysis.periodic.baselines import needleman_wunsch, nw_star, smith_waterman
from analysis.periodic.fitness import (
    Coded,
    Symbol,
    distinct_periods,
    encode,
    naive_step,
    periods,
    sequence_fitness,
    tables,
    training_patterns,
)
from analysis.periodic.ga import PAPER_GA, PAPER_GA_K, GAOptions, run_ga

__all__ = [
    "METHODS",
    "PAPER_GA",
    "PAPER_GA_K",
    "TUNED_GA",
    "TUNED_GA_K",
    "GAOptions",
    "clean",
    "distinct_periods",
    "naive_psa",
    "periods",
    "sequence_fitness",
    "training_patterns",
]

METHODS = ("naive", "nw*", "ga", "ga-k", "nw", "sw")

# f_e standing in for the ∞ of eq 6.21 in NaivePSA: larger than any positional distance.
NAIVE_F_E = 1.0e6

TUNED_GA_K = GAOptions(mutation="prior")
TUNED_GA = GAOptions(mutation="random", seeded=False)


def clean(
    sequence: Sequence[Symbol],
    patterns: Sequence[Sequence[Symbol]],
    method: str = "ga-k",
    seed: int = 0,
    options: GAOptions | None = None,
) -> list[int]:
    """Sorted indices of the members of ``sequence`` kept by periodic sequence analysis.

    sequence: N hashable symbols (landmark types). patterns: training periods; a pattern written
    without its closing heading member (``[1, 2]``) is closed (``[1, 2, 1]``). seed: seeds the
    GAs (the other methods are deterministic). options: GA parameters for "ga"/"ga-k".
    Raises ValueError for an unknown method or an empty pattern.
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {', '.join(METHODS)}")
    coded = encode(sequence, patterns)
    if len(sequence) == 0:
        return []
    mask = _MASKERS[method](coded, seed, options)
    return [int(i) for i in np.flatnonzero(mask)]


def naive_psa(sequence: Sequence[Symbol], patterns: Sequence[Sequence[Symbol]]) -> list[int]:
    """NaivePSA (Alg 2): kept indices after repeatedly removing each period's worst member."""
    return clean(sequence, patterns, method="naive")


def _naive_mask(coded: Coded, seed: int = 0, options: GAOptions | None = None) -> np.ndarray:
    """Alg 2: remove, in every period, the member of largest positive 𝔉 until none is left.

    Also stops when the sequence fitness (6.24) does not change, the printed stop criterion.
    """
    mask = np.ones(coded.symbols.shape[0], dtype=bool)
    previous = np.inf
    while True:
        total, marks = naive_step(coded.symbols[mask], tables(coded), NAIVE_F_E)
        if not marks.any() or total == previous:
            return mask
        mask[np.flatnonzero(mask)[marks]] = False
        previous = total


def _nw_star_mask(coded: Coded, seed: int = 0, options: GAOptions | None = None) -> np.ndarray:
    return nw_star(coded.symbols, coded.pattern_syms, coded.pattern_len)


def _concatenated_patterns(coded: Coded) -> np.ndarray:
    rows = [coded.pattern_syms[r, : coded.pattern_len[r]] for r in range(coded.pattern_len.size)]
    return np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)


def _nw_mask(coded: Coded, seed: int = 0, options: GAOptions | None = None) -> np.ndarray:
    return needleman_wunsch(_concatenated_patterns(coded), coded.symbols)


def _sw_mask(coded: Coded, seed: int = 0, options: GAOptions | None = None) -> np.ndarray:
    return smith_waterman(_concatenated_patterns(coded), coded.symbols)


def _ga_mask(coded: Coded, seed: int, options: GAOptions | None, default: GAOptions) -> np.ndarray:
    opt = options or default
    rng = np.random.default_rng(seed)
    starts = [_naive_mask(coded)] if opt.seeded else []
    return run_ga(coded.symbols, tables(coded), opt, rng, starts)


def _ga_random_mask(coded: Coded, seed: int, options: GAOptions | None) -> np.ndarray:
    return _ga_mask(coded, seed, options, TUNED_GA)


def _ga_prior_mask(coded: Coded, seed: int, options: GAOptions | None) -> np.ndarray:
    return _ga_mask(coded, seed, options, TUNED_GA_K)


_MASKERS = {
    "naive": _naive_mask,
    "nw*": _nw_star_mask,
    "nw": _nw_mask,
    "sw": _sw_mask,
    "ga": _ga_random_mask,
    "ga-k": _ga_prior_mask,
}
