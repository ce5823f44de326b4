"""Periods and fitness of periodic symbol sequences (thesis 004, section 6.2, eqs 6.14–6.24, Alg 5).

Readable reference functions mirror the equations; the numba kernels at the bottom compute the
same numbers on integer-coded sequences and are what the algorithms call.

Conventions. A sequence ``S`` is a list of hashable symbols (landmark types, letters). A *period*
``ν(S, i) = S[i .. κ(S, i)]`` runs from member ``i`` to the next member with the same symbol, both
ends included (eqs 6.15–6.16); its first and last members are its *heading* members. Python indices
are 0-based; the positional heuristic of eq 6.21 uses the paper's 1-based positions internally.
Fitness values are penalties: 0 is a perfectly fitting member, larger is worse.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

Symbol = Hashable
# (pattern_syms, pattern_len, head_first, head_count): see :class:`Coded`.
Tables = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]

# How Alg 5 treats a period whose share of penalised members exceeds r_e.
INVERT_PROSE = 0  # the prose: penalised members become fit (0) and fit members get f_e
INVERT_DROP = 1  # the pseudo-code as printed: the period contributes nothing
INVERSION_RULES = {"prose": INVERT_PROSE, "drop": INVERT_DROP}


# ---------------------------------------------------------------- reference (readable) path


def kappa(sequence: Sequence[Symbol], i: int) -> int | None:
    """κ(S, i) (eq 6.16): index of the next member equal to ``S[i]``, or None when there is none."""
    for n in range(i + 1, len(sequence)):
        if sequence[n] == sequence[i]:
            return n
    return None


def periods(sequence: Sequence[Symbol]) -> list[tuple[int, int]]:
    """All periods of ``S`` as ``(i, κ(S, i))`` index pairs, in order of ``i`` (eqs 6.15, 6.17).

    Every occurrence counts: the fitness sums (6.23–6.24) run over each period instance.
    """
    pairs = []
    for i in range(len(sequence)):
        k = kappa(sequence, i)
        if k is not None:
            pairs.append((i, k))
    return pairs


def distinct_periods(
    sequence: Sequence[Symbol], heads: set[Symbol] | None = None
) -> set[tuple[Symbol, ...]]:
    """𝒩(S) as a set of distinct periods (eq 6.17), optionally only those headed by ``heads``.

    The thesis lists 𝒩(S) only for the heads of its training patterns (eqs 6.19, 6.26): periods
    headed by another symbol match no pattern and never change the fitness.
    """
    found = {tuple(sequence[i : k + 1]) for i, k in periods(sequence)}
    return found if heads is None else {p for p in found if p[0] in heads}


def training_patterns(sequences: Sequence[Sequence[Symbol]]) -> list[list[Symbol]]:
    """Training patterns 𝒫: the distinct periods of clean training sequences, first seen first."""
    seen: dict[tuple[Symbol, ...], None] = {}
    for seq in sequences:
        for i, k in periods(seq):
            seen.setdefault(tuple(seq[i : k + 1]), None)
    return [list(p) for p in seen]


def matching_patterns(
    period: Sequence[Symbol], patterns: Sequence[Sequence[Symbol]]
) -> list[Sequence[Symbol]]:
    """ℳ(ν, 𝒫) (eq 6.20): the training patterns headed by the same member as ``period``."""
    return [p for p in patterns if len(p) > 0 and p[0] == period[0]]


def member_distance(period: Sequence[Symbol], i: int, pattern: Sequence[Symbol]) -> float:
    """ℌ(ν, i, ν̄) (eq 6.21): min_k |k − i·|ν̄|/|ν|| over pattern positions k holding ν(i); ∞ if none.

    ``i`` is 0-based; the formula uses the 1-based position ``i + 1`` as the paper does.
    """
    target = (i + 1) * len(pattern) / len(period)
    dists = [abs(k + 1 - target) for k, s in enumerate(pattern) if s == period[i]]
    return min(dists) if dists else math.inf


def member_fitness(
    period: Sequence[Symbol],
    i: int,
    patterns: Sequence[Sequence[Symbol]],
    f_e: float = math.inf,
) -> float:
    """𝔉(ν, i, 𝒫, f_e) (eq 6.22): sum of ℌ over ℳ(ν, 𝒫); a member absent from a pattern costs f_e.

    With the default ``f_e = ∞`` this is eq 6.22 exactly; the GA (Alg 5) uses a finite f_e.
    """
    total = 0.0
    for pattern in matching_patterns(period, patterns):
        h = member_distance(period, i, pattern)
        total += f_e if math.isinf(h) else h
    return total


def period_fitness(
    period: Sequence[Symbol], patterns: Sequence[Sequence[Symbol]], f_e: float = math.inf
) -> float:
    """𝔉(ν, 𝒫) (eq 6.23): sum of the member fitness over the members of one period."""
    return sum(member_fitness(period, i, patterns, f_e) for i in range(len(period)))


def sequence_fitness(
    sequence: Sequence[Symbol], patterns: Sequence[Sequence[Symbol]], f_e: float = math.inf
) -> float:
    """𝔉(S, 𝒫) (eq 6.24): sum of the period fitness over every period instance of ``S``."""
    return sum(period_fitness(sequence[i : k + 1], patterns, f_e) for i, k in periods(sequence))


def chromosome_fitness(
    j: int,
    sequence: Sequence[Symbol],
    patterns: Sequence[Sequence[Symbol]],
    *,
    f_e: float,
    r_e: float,
    inversion: str = "prose",
) -> float:
    """CFitness(s_j, S, 𝒫, f_e, r_e) (Alg 5): member ``j``'s fitness summed over its periods.

    In a period where more than ``|ν|·r_e`` members have a positive fitness, the values are
    inverted (``inversion="prose"``: 0 ↔ f_e, positive → 0, as the text describes) or the period
    is ignored (``"drop"``: what the printed pseudo-code computes).
    """
    total = 0.0
    for a, b in periods(sequence):
        if not a <= j <= b:
            continue
        period = sequence[a : b + 1]
        values = [member_fitness(period, m, patterns, f_e) for m in range(len(period))]
        n_e = sum(v > 0 for v in values)
        f = values[j - a]
        if n_e <= len(period) * r_e:
            total += f
        elif inversion == "prose":
            total += f_e if f == 0 else 0.0
    return total


def phenotype_fitness(
    sequence: Sequence[Symbol],
    patterns: Sequence[Sequence[Symbol]],
    *,
    f_e: float,
    r_e: float,
    inversion: str = "prose",
) -> float:
    """Fitness(S, 𝒫, f_e, r_e) (eq 6.31): sum of CFitness over all members."""
    return sum(
        chromosome_fitness(j, sequence, patterns, f_e=f_e, r_e=r_e, inversion=inversion)
        for j in range(len(sequence))
    )


# ---------------------------------------------------------------- integer coding


@dataclass(frozen=True)
class Coded:
    """A sequence and its training patterns coded as integers for the kernels.

    ``symbols``: (N,) int64 codes of the sequence members. ``pattern_syms``: (n_patterns, max_len)
    int64, padded with -1, sorted by head. ``pattern_len``: (n_patterns,). ``head_first`` and
    ``head_count``: (n_codes,) first row and number of rows of the patterns headed by each code.
    """

    symbols: np.ndarray
    pattern_syms: np.ndarray
    pattern_len: np.ndarray
    head_first: np.ndarray
    head_count: np.ndarray


def close_pattern(pattern: Sequence[Symbol]) -> list[Symbol]:
    """A training period with its closing heading member (``[1, 2]`` → ``[1, 2, 1]``)."""
    if len(pattern) == 0:
        raise ValueError("a training pattern must not be empty")
    out = list(pattern)
    if len(out) == 1 or out[-1] != out[0]:
        out.append(out[0])
    return out


def encode(sequence: Sequence[Symbol], patterns: Sequence[Sequence[Symbol]]) -> Coded:
    """Code ``sequence`` and ``patterns`` (closed with :func:`close_pattern`) as integers."""
    closed = [close_pattern(p) for p in patterns]
    codes: dict[Symbol, int] = {}
    for s in [s for p in closed for s in p] + list(sequence):
        codes.setdefault(s, len(codes))
    closed.sort(key=lambda p: codes[p[0]])  # the kernels find a head's patterns as one block
    max_len = max((len(p) for p in closed), default=1)
    syms = np.full((len(closed), max_len), -1, dtype=np.int64)
    head_first = np.zeros(len(codes), dtype=np.int64)
    head_count = np.zeros(len(codes), dtype=np.int64)
    for row, p in enumerate(closed):
        syms[row, : len(p)] = [codes[s] for s in p]
        head = codes[p[0]]
        if head_count[head] == 0:
            head_first[head] = row
        head_count[head] += 1
    lens = np.array([len(p) for p in closed], dtype=np.int64)
    seq = np.array([codes[s] for s in sequence], dtype=np.int64)
    return Coded(seq, syms, lens, head_first, head_count)


# ---------------------------------------------------------------- numba kernels (fast path)


@njit(cache=True)
def next_same(t: np.ndarray, n_codes: int) -> np.ndarray:
    """κ for every member of the coded sequence ``t`` (N,), -1 where there is none."""
    nxt = np.full(t.shape[0], -1, dtype=np.int64)
    last = np.full(n_codes, -1, dtype=np.int64)
    for j in range(t.shape[0] - 1, -1, -1):
        nxt[j] = last[t[j]]
        last[t[j]] = j
    return nxt


@njit(cache=True)
def period_member_fitness(x: np.ndarray, c: Tables, f_e: float, out: np.ndarray) -> int:
    """Fill ``out[:len(x)]`` with 𝔉(ν, i, 𝒫, f_e) of each member of the coded period ``x``.

    ``c`` is (pattern_syms, pattern_len, head_first, head_count) of :class:`Coded`. Returns the
    number of members with a positive value (N_e of Alg 5).
    """
    syms, lens, first, count = c
    head, length = x[0], x.shape[0]
    n_e = 0
    for m in range(length):
        total = 0.0
        for p in range(first[head], first[head] + count[head]):
            target = (m + 1) * lens[p] / length
            best = np.inf
            for k in range(lens[p]):
                if syms[p, k] == x[m]:
                    best = min(best, abs(k + 1 - target))
            total += f_e if best == np.inf else best
        out[m] = total
        n_e += total > 0
    return n_e


@njit(cache=True)
def member_cfitness(t: np.ndarray, c: Tables, params: np.ndarray) -> np.ndarray:
    """CFitness (Alg 5) of every member of the coded sequence ``t`` (N,) → (N,) float.

    ``params`` = (f_e, r_e, inversion rule code).
    """
    f_e, r_e, rule = params[0], params[1], int(params[2])
    n = t.shape[0]
    cf = np.zeros(n)
    buf = np.empty(n)
    nxt = next_same(t, c[3].shape[0])
    for a in range(n):
        b = nxt[a]
        if b < 0 or c[3][t[a]] == 0:
            continue
        length = b - a + 1
        inverted = period_member_fitness(t[a : b + 1], c, f_e, buf) > length * r_e
        for m in range(length):
            if not inverted:
                cf[a + m] += buf[m]
            elif rule == INVERT_PROSE and buf[m] == 0:
                cf[a + m] += f_e
    return cf


@njit(cache=True)
def population_fitness(
    symbols: np.ndarray, masks: np.ndarray, c: Tables, params: np.ndarray
) -> np.ndarray:
    """Eq 6.31 for each individual: ``masks`` (P, N) bool of kept members → (P,) float."""
    out = np.empty(masks.shape[0])
    for p in range(masks.shape[0]):
        out[p] = member_cfitness(symbols[masks[p]], c, params).sum()
    return out


def tables(coded: Coded) -> Tables:
    """The pattern tables of ``coded`` in the tuple order the kernels take."""
    return (coded.pattern_syms, coded.pattern_len, coded.head_first, coded.head_count)


@njit(cache=True)
def naive_step(t: np.ndarray, c: Tables, f_e: float) -> tuple[float, np.ndarray]:
    """One pass of NaivePSA (Alg 2) over the coded sequence ``t`` (N,).

    Returns 𝔉(S, 𝒫) (eq 6.24, no inversion) and the (N,) bool marks of the members to remove:
    in every period, the first member with the largest positive 𝔉(ν, i, 𝒫).
    """
    n = t.shape[0]
    marks = np.zeros(n, dtype=np.bool_)
    buf = np.empty(n)
    nxt = next_same(t, c[3].shape[0])
    total = 0.0
    for a in range(n):
        b = nxt[a]
        if b < 0 or c[3][t[a]] == 0:
            continue
        period_member_fitness(t[a : b + 1], c, f_e, buf)
        worst = 0
        for m in range(b - a + 1):
            total += buf[m]
            if buf[m] > buf[worst]:
                worst = m
        if buf[worst] > 0:
            marks[a + worst] = True
    return total, marks
