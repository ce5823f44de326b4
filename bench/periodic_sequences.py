"""Random periodic sequences with ground truth and the metrics of thesis 004, 6.4 (eqs 6.38–6.39).

Protocol (6.4.1). A *training sequence* splits the whole 26-letter alphabet into ``k`` distinct
periods of 4–10 items each and repeats every period 4–10 times, closing each block with its
heading member (the thesis's example ``[PFGYVK]^5 ...`` reads ``PFGYVKPFGYVK...P``). With
disjoint sub-alphabets (eq 6.7) and every period holding 4–10 letters, 26 letters allow only
k = 4–6 of the stated 4–10 distinct periods: we draw k uniformly from the feasible range.
The training patterns 𝒫 are the k periods (with their closing head). Each *test sample* copies
the training sequence and, independently per ground-truth member, inserts before it an in-period
extraneous member (a letter of the same period) with probability 0.1 and an out-of-period one
(any other letter) with probability 0.2 (in random order when both), and drops the member with
probability 0.1.

Metrics (6.38), with ``S^G`` the ground truth: tp = ground-truth members kept; tn = ground-truth
members absent from the output and already absent from the sample (the thesis's definition:
the missing members); fp = extraneous members kept; fn = ground-truth members in the sample that
the method removed. Rates (6.39) plus recall r = tp/(tp+fn) (Table 6.1's ``r``).
"""

from __future__ import annotations

import string
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RandomPeriodicOptions:
    """Generator parameters; ranges are inclusive (low, high)."""

    alphabet: str = string.ascii_uppercase
    n_periods: tuple[int, int] = (4, 10)
    items: tuple[int, int] = (4, 10)
    repeats: tuple[int, int] = (4, 10)
    in_rate: float = 0.1
    out_rate: float = 0.2
    missing_rate: float = 0.1


@dataclass(frozen=True)
class TrainingSequence:
    """A clean periodic sequence ``S^G`` and its training periods 𝒫 (each with its closing head)."""

    sequence: tuple[str, ...]
    patterns: tuple[tuple[str, ...], ...]


@dataclass(frozen=True)
class PeriodicSample:
    """A corrupted copy of a training sequence.

    sequence: the test sample S̄. truth: per sample member, its index in ``S^G`` or -1 for an
    extraneous member. n_truth: |S^G|.
    """

    sequence: tuple[str, ...]
    truth: tuple[int, ...]
    n_truth: int


@dataclass(frozen=True)
class Confusion:
    """Counts of eq 6.38."""

    tp: int
    tn: int
    fp: int
    fn: int


@dataclass(frozen=True)
class PeriodicScores:
    """Rates of eq 6.39 (and recall); an empty denominator gives 1.0 for tnr, 0.0 otherwise."""

    accuracy: float
    recall: float
    tnr: float
    fnr: float
    fdr: float
    precision: float


def _partition(n: int, k: int, low: int, high: int, rng: np.random.Generator) -> list[int]:
    """Random sizes of k parts in [low, high] summing to n (n must be feasible)."""
    sizes = [low] * k
    for _ in range(n - low * k):
        open_parts = [i for i in range(k) if sizes[i] < high]
        sizes[open_parts[int(rng.integers(len(open_parts)))]] += 1
    return sizes


def random_training_sequence(
    rng: np.random.Generator, options: RandomPeriodicOptions | None = None
) -> TrainingSequence:
    """One training sequence: the alphabet split into k periods, each repeated 4–10 times."""
    o = options or RandomPeriodicOptions()
    n = len(o.alphabet)
    k_low = max(o.n_periods[0], -(-n // o.items[1]))
    k_high = min(o.n_periods[1], n // o.items[0])
    if k_low > k_high:
        raise ValueError("no partition of the alphabet fits the period and item ranges")
    k = int(rng.integers(k_low, k_high + 1))
    letters = list(rng.permutation(list(o.alphabet)))
    sequence: list[str] = []
    patterns = []
    for size in _partition(n, k, o.items[0], o.items[1], rng):
        cycle, letters = [str(x) for x in letters[:size]], letters[size:]
        repeats = int(rng.integers(o.repeats[0], o.repeats[1] + 1))
        sequence += cycle * repeats + [cycle[0]]
        patterns.append((*cycle, cycle[0]))
    return TrainingSequence(tuple(sequence), tuple(patterns))


def corrupt(
    training: TrainingSequence,
    rng: np.random.Generator,
    options: RandomPeriodicOptions | None = None,
) -> PeriodicSample:
    """A test sample: in-period / out-of-period insertions and missing members (module doc)."""
    o = options or RandomPeriodicOptions()
    block_of = {s: b for b, p in enumerate(training.patterns) for s in p}
    seq: list[str] = []
    truth: list[int] = []
    for g, symbol in enumerate(training.sequence):
        own = list(dict.fromkeys(training.patterns[block_of[symbol]]))
        others = [s for s in o.alphabet if s not in own]
        inserted = []
        if rng.random() < o.in_rate:
            inserted.append(own[int(rng.integers(len(own)))])
        if rng.random() < o.out_rate:
            inserted.append(others[int(rng.integers(len(others)))])
        if len(inserted) == 2 and rng.random() < 0.5:  # no fixed order: ties stay 50/50
            inserted.reverse()
        seq += inserted
        truth += [-1] * len(inserted)
        if rng.random() >= o.missing_rate:
            seq.append(symbol)
            truth.append(g)
    return PeriodicSample(tuple(seq), tuple(truth), len(training.sequence))


def confusion(sample: PeriodicSample, kept: Sequence[int]) -> Confusion:
    """Eq 6.38 for the kept sample indices ``kept``."""
    truth = np.asarray(sample.truth, dtype=np.int64)
    keep = np.zeros(truth.size, dtype=bool)
    keep[np.asarray(kept, dtype=np.int64)] = True
    real = truth >= 0
    tp = int((keep & real).sum())
    fp = int((keep & ~real).sum())
    fn = int((~keep & real).sum())
    tn = sample.n_truth - int(real.sum())
    return Confusion(tp, tn, fp, fn)


def _ratio(num: int, den: int, empty: float = 0.0) -> float:
    return num / den if den else empty


def scores(c: Confusion) -> PeriodicScores:
    """Eq 6.39: accuracy, recall, tnr, fnr, fdr and precision from the counts."""
    return PeriodicScores(
        accuracy=_ratio(c.tp + c.tn, c.tp + c.tn + c.fp + c.fn),
        recall=_ratio(c.tp, c.tp + c.fn),
        tnr=_ratio(c.tn, c.tn + c.fp, empty=1.0),
        fnr=_ratio(c.fn, c.tp + c.fn),
        fdr=_ratio(c.fp, c.tp + c.fp),
        precision=_ratio(c.tp, c.tp + c.fp),
    )


def experiment(
    n_training: int = 5,
    n_tests: int = 10,
    seed: int = 0,
    options: RandomPeriodicOptions | None = None,
) -> list[tuple[TrainingSequence, PeriodicSample]]:
    """The 6.4.1 data set: ``n_training`` training sequences × ``n_tests`` samples each."""
    rng = np.random.default_rng(seed)
    data = []
    for _ in range(n_training):
        training = random_training_sequence(rng, options)
        data += [(training, corrupt(training, rng, options)) for _ in range(n_tests)]
    return data


def mean_scores(all_scores: Sequence[PeriodicScores]) -> PeriodicScores:
    """Per-sample rates averaged over samples (the thesis reports averages)."""
    fields = PeriodicScores.__dataclass_fields__
    return PeriodicScores(
        **{f: float(np.mean([getattr(s, f) for s in all_scores])) for f in fields}
    )
