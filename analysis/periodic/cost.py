"""Cyclic-alignment cost of a candidate sequence: our fitness for the tuned GA (not in the thesis).

Why. Eq 6.21 compares a member's position with a scaled position in the training period, so one
missing or inserted member shifts every later member of its period and makes correct members
look extraneous; a missing heading member merges two periods into one that looks half
extraneous; members outside every period are never penalised (the thesis notes this for 6.30);
and removing members never costs anything, so the empty sequence (fitness 0) beats any ground
truth with a missing member. Searches on it lose correct members: the thesis's GA^K reaches an
accuracy of 0.69–0.80 on the 6.4.1 protocol (docs/sections/eval_periodic.md).

What. The candidate's periods ``ν`` (eq 6.15) headed by a training-pattern head ``h`` are aligned
with the training cycle of ``h`` repeated any number of times (``h c_1 … c_m (h c_1 … c_m)* h``):
an interior member left unmatched is *extraneous* (cost ``f_e``), a cycle position left unmatched
is *missing* (cost ``c_m``; a missing inner head is how two merged periods are explained). As in
Alg 5, a period most of whose interior is foreign to the pattern (share > ``r_e``) is blamed on
its heads: it costs ``c_h`` and leaves its members to their own periods. A *stretch* of members
outside every other period (around a block boundary whose heading member is missing, or
extraneous members between blocks) is read as the end of the previous block (its last head
missing), extraneous members, then the start of the next block (its first head missing). The
cost of a candidate is the sum, plus ``c_d`` per member removed from the sample.

Weights ``w = (f_e, c_m, r_e, c_h, c_d)``. DP for one period interior ``x_1..x_n`` against the
cycle ``c_0..c_{L-1}`` (``c_0 = h``), state ``s`` = next expected cycle position, from
``D[0, 1] = 0`` to ``D[n, 0]``::

    D[i, s] = min(D[i-1, s] + f_e,                  # x_i extraneous
                  D[i-1, s-1]  if x_i = c_{s-1})    # x_i matches c_{s-1}
    D[i, s] = min(D[i, s], D[i, s-1] + c_m)         # c_{s-1} missing (relaxed around the cycle)
"""

from __future__ import annotations

import numpy as np
from numba import njit

from analysis.periodic.fitness import Tables, next_same

# Memo of period and stretch costs: (keys, values) of an open-addressing hash table whose empty
# slots hold NaN values (a numba typed dict made the first compile ~7 s longer).
CostCache = tuple[np.ndarray, np.ndarray]
INVERTED = -1.0  # memoised in place of the cost of a period blamed on its heads (it costs c_h)
PROBES = 32  # a key not found within this many slots is simply not memoised


@njit(cache=True)
def _fill(x: np.ndarray, cycle: np.ndarray, f_e: float, c_m: float) -> np.ndarray:
    """The DP matrix (n+1, L) of the module docstring."""
    n, size = x.shape[0], cycle.shape[0]
    d = np.full((n + 1, size), np.inf)
    d[0, 1 % size] = 0.0
    for i in range(n + 1):
        if i > 0:
            for s in range(size):
                d[i, s] = d[i - 1, s] + f_e
            for s in range(size):
                if cycle[s] == x[i - 1]:
                    t = (s + 1) % size
                    d[i, t] = min(d[i, t], d[i - 1, s])
        for k in range(2 * size):  # two laps reach the fixed point of the missing moves
            s, t = k % size, (k + 1) % size
            d[i, t] = min(d[i, t], d[i, s] + c_m)
    return d


@njit(cache=True)
def _traceback(
    d: np.ndarray, x: np.ndarray, cycle: np.ndarray, f_e: float, out: np.ndarray
) -> None:
    """Flag in ``out`` (n,) the members left extraneous on the optimal path to ``D[n, 0]``.

    Ties prefer a match, then an extraneous member, then a missing one. Every missing move
    strictly lowers the cost, so a row's chain of them ends.
    """
    size = cycle.shape[0]
    i, s = x.shape[0], 0
    while i > 0:
        prev = (s - 1) % size
        if cycle[prev] == x[i - 1] and d[i, s] == d[i - 1, prev]:
            i, s = i - 1, prev
        elif d[i, s] == d[i - 1, s] + f_e:
            out[i - 1] = True
            i -= 1
        else:
            s = prev


@njit(cache=True)
def _cycle(tb: Tables, p: int, reverse: bool) -> np.ndarray:
    """Pattern row ``p`` without its closing head; reversed after the head (for block starts)."""
    size = tb[1][p] - 1
    cyc = np.empty(size, dtype=np.int64)
    cyc[0] = tb[0][p, 0]
    for k in range(1, size):
        cyc[k] = tb[0][p, size - k if reverse else k]
    return cyc


@njit(cache=True)
def _foreign(x: np.ndarray, head: int, tb: Tables) -> int:
    """Number of members of ``x`` whose symbol occurs in no pattern headed by ``head``."""
    syms, lens, first, count = tb
    n = 0
    for v in x:
        found = False
        for p in range(first[head], first[head] + count[head]):
            for k in range(lens[p]):
                found = found or syms[p, k] == v
        n += not found
    return n


@njit(cache=True)
def _period(x: np.ndarray, head: int, tb: Tables, w: np.ndarray, out: np.ndarray) -> float:
    """Least cost of the period interior ``x`` over the patterns headed by ``head``; flags its
    extraneous members in ``out`` (n,) unless ``out`` is empty."""
    best, best_d, best_cyc = np.inf, np.empty((0, 0)), np.empty(0, dtype=np.int64)
    for p in range(tb[2][head], tb[2][head] + tb[3][head]):
        cyc = _cycle(tb, p, False)
        d = _fill(x, cyc, w[0], w[1])
        if d[x.shape[0], 0] < best:
            best, best_d, best_cyc = d[x.shape[0], 0], d, cyc
    if out.shape[0] > 0 and best_cyc.shape[0] > 0:
        _traceback(best_d, x, best_cyc, w[0], out)
    return best


@njit(cache=True)
def _edge_costs(
    x: np.ndarray, head: int, tb: Tables, w: np.ndarray, reverse: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Cost of every prefix ``x[:k]`` read as cycles after ``head`` whose closing head is missing
    (reverse: ``x`` reversed, a block start whose opening head is missing): (n+1,) costs with
    ``c_m`` for the missing head (0 for k = 0, inf without a pattern) and their pattern rows."""
    n, c_m = x.shape[0], w[1]
    costs = np.full(n + 1, np.inf)
    rows = np.full(n + 1, -1, dtype=np.int64)
    costs[0] = 0.0
    if head < 0:
        return costs, rows
    for p in range(tb[2][head], tb[2][head] + tb[3][head]):
        d = _fill(x, _cycle(tb, p, reverse), w[0], c_m)
        for k in range(1, n + 1):
            if d[k, 0] + c_m < costs[k]:
                costs[k], rows[k] = d[k, 0] + c_m, p
    return costs, rows


@njit(cache=True)
def _edge_marks(x: np.ndarray, cyc: np.ndarray, w: np.ndarray, out: np.ndarray) -> None:
    """Flag the extraneous members of :func:`_edge_costs`'s alignment of ``x`` with ``cyc``."""
    if x.shape[0] > 0:
        _traceback(_fill(x, cyc, w[0], w[1]), x, cyc, w[0], out)


@njit(cache=True)
def _stretch(
    x: np.ndarray, ends: tuple[int, int], tb: Tables, w: np.ndarray, out: np.ndarray
) -> float:
    """Cost of a stretch ``x`` = end of the block of ``ends[0]`` (the head just before, -1 at
    the start) + extraneous members + start of the block of ``ends[1]`` (the head just after,
    -1 at the end); flags the extraneous members in ``out`` unless it is empty. With no
    neighbour at all nothing is known and the cost is 0."""
    n, f_e = x.shape[0], w[0]
    if ends[0] < 0 and ends[1] < 0:
        return 0.0
    pre, pre_rows = _edge_costs(x, ends[0], tb, w, False)
    rev = x[::-1].copy()
    suf, suf_rows = _edge_costs(rev, ends[1], tb, w, True)
    best, cut_i, cut_j = np.inf, 0, 0
    lead, lead_i = np.inf, 0  # min over i <= j of pre[i] - f_e * i
    for j in range(n + 1):
        if pre[j] - f_e * j < lead:
            lead, lead_i = pre[j] - f_e * j, j
        if lead + f_e * j + suf[n - j] < best:
            best, cut_i, cut_j = lead + f_e * j + suf[n - j], lead_i, j
    if out.shape[0] > 0:
        if cut_i > 0:
            _edge_marks(x[:cut_i].copy(), _cycle(tb, pre_rows[cut_i], False), w, out[:cut_i])
        out[cut_i:cut_j] = True
        if cut_j < n:
            tail = np.zeros(n - cut_j, dtype=np.bool_)
            _edge_marks(rev[: n - cut_j].copy(), _cycle(tb, suf_rows[n - cut_j], True), w, tail)
            out[cut_j:] = tail[::-1]
    return best


@njit(cache=True)
def _key(x: np.ndarray, first: int, second: int) -> int:
    """64-bit FNV-1a hash of (first, second, x): the cache key of a period or a stretch."""
    h = np.int64(-3750763034362895579)  # the FNV offset basis as a signed 64-bit integer
    for v in (first + 3, second + 3, x.shape[0]):
        h = (h ^ np.int64(v)) * np.int64(1099511628211)
    for v in x:
        h = (h ^ np.int64(v)) * np.int64(1099511628211)
    return int(h)


@njit(cache=True)
def _period_cost(
    x: np.ndarray, head: int, tb: Tables, w: np.ndarray, cache: CostCache
) -> tuple[float, bool]:
    """(cost, blamed on the heads) of the period interior ``x``, memoised in ``cache``."""
    key = _key(x, head, -2)
    cost = _recall(cache, key)
    if np.isnan(cost):
        if _foreign(x, head, tb) > w[2] * x.shape[0]:
            cost = INVERTED
        else:
            cost = _period(x, head, tb, w, np.zeros(0, dtype=np.bool_))
        _remember(cache, key, cost)
    return (w[3], True) if cost == INVERTED else (cost, False)


@njit(cache=True)
def _periods_cost(
    t: np.ndarray, tb: Tables, w: np.ndarray, scores: np.ndarray, cache: CostCache
) -> tuple[float, np.ndarray]:
    """Sum of the period costs of ``t`` and the (N,) bool members of the periods kept.

    A period most of whose interior is foreign (share > r_e) costs c_h and covers nothing: its
    members are left to their own periods or to a stretch. Unless ``scores`` is empty, adds to
    it f_e for each extraneous member and half of each period's missing cost (or c_h) to each
    of its two heading members.
    """
    marks = scores.shape[0] > 0
    covered = np.zeros(t.shape[0], dtype=np.bool_)
    total = 0.0
    nxt = next_same(t, tb[3].shape[0])
    for a in range(t.shape[0]):
        b = nxt[a]
        if b < 0 or tb[3][t[a]] == 0:
            continue
        x = t[a + 1 : b]
        cost, inverted = _period_cost(x, t[a], tb, w, cache)
        total += cost
        if not inverted:
            covered[a : b + 1] = True
        if marks:
            flags = np.zeros(x.shape[0], dtype=np.bool_)
            if not inverted:
                _period(x, t[a], tb, w, flags)
            share = (cost - w[0] * flags.sum()) / 2
            scores[a] += share
            scores[b] += share
            scores[a + 1 : b] += w[0] * flags
    return total, covered


def candidate_cost(t: np.ndarray, tb: Tables, w: np.ndarray, scores: np.ndarray) -> float:
    """Alignment cost of the coded candidate ``t`` (N,), without the removal cost ``c_d``.

    Unless ``scores`` is empty, it receives (N,) each member's share of the cost, what
    MutatePrior ranks (extraneous members f_e, heading members their share of missing costs).
    """
    return float(_candidate_cost(t, tb, w, scores, new_cache(8)))


@njit(cache=True)
def _candidate_cost(
    t: np.ndarray, tb: Tables, w: np.ndarray, scores: np.ndarray, cache: CostCache
) -> float:
    n = t.shape[0]
    marks = scores.shape[0] > 0
    total, covered = _periods_cost(t, tb, w, scores, cache)
    j = 0
    while j < n:
        k = j
        while k < n and not covered[k]:
            k += 1
        if k > j:
            ends = (t[j - 1] if j > 0 else -1, t[k] if k < n else -1)
            x = t[j:k].copy()
            key = _key(x, ends[0], ends[1])
            cost = _recall(cache, key)
            if marks or np.isnan(cost):
                flags = np.zeros(k - j if marks else 0, dtype=np.bool_)
                cost = _stretch(x, ends, tb, w, flags)
                _remember(cache, key, cost)
                scores[j:k] += w[0] * flags
            total += cost
        j = k + 1
    return total


def new_cache(size_log2: int = 14) -> CostCache:
    """An empty memo of period and stretch costs, valid for one pattern set and one ``w``."""
    return np.zeros(1 << size_log2, dtype=np.int64), np.full(1 << size_log2, np.nan)


@njit(cache=True)
def _slot(cache: CostCache, key: int) -> int:
    """Slot holding ``key`` or the empty slot where it goes; -1 when the probes run out."""
    keys, values = cache
    mask = keys.shape[0] - 1
    i = key & mask
    for _ in range(PROBES):
        if np.isnan(values[i]) or keys[i] == key:
            return i
        i = (i + 1) & mask
    return -1


@njit(cache=True)
def _recall(cache: CostCache, key: int) -> float:
    """The memoised cost of ``key``, NaN when there is none."""
    i = _slot(cache, key)
    return np.nan if i < 0 else cache[1][i]


@njit(cache=True)
def _remember(cache: CostCache, key: int, cost: float) -> None:
    i = _slot(cache, key)
    if i >= 0:
        cache[0][i], cache[1][i] = key, cost


@njit(cache=True)
def population_cost(
    symbols: np.ndarray, masks: np.ndarray, tb: Tables, w: np.ndarray, cache: CostCache
) -> np.ndarray:
    """(P, N) bool masks over the coded sample ``symbols`` (N,) → (P,) cost + c_d per removal.

    ``cache`` (from :func:`new_cache`) memoises period and stretch costs across calls: a GA's
    individuals share most of their periods.
    """
    out = np.empty(masks.shape[0])
    none = np.zeros(0)
    for p in range(masks.shape[0]):
        kept = symbols[masks[p]]
        removed = symbols.shape[0] - kept.shape[0]
        out[p] = _candidate_cost(kept, tb, w, none, cache) + w[4] * removed
    return out


@njit(cache=True)
def member_scores(t: np.ndarray, tb: Tables, w: np.ndarray, cache: CostCache) -> np.ndarray:
    """Each member's share of the cost of the coded candidate ``t`` (N,) → (N,)."""
    scores = np.zeros(t.shape[0])
    if t.shape[0] > 0:
        _candidate_cost(t, tb, w, scores, cache)
    return scores
