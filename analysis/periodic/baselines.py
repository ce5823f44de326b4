"""String-alignment baselines for periodic sequence analysis (thesis 004, 6.2.4 and 6.4.1).

Each baseline keeps the sample members that an alignment pairs with an identical pattern symbol
and drops the rest. Scores: match +1, mismatch −1, gap −1 (the classic unit scheme; the thesis
does not give its scores).

- Needleman-Wunsch (global) and Smith-Waterman (local) align the whole sample against the
  concatenation of the training patterns, as ``NeedlemanWunsch*`` initialises ``S_1`` (Alg 3).
  Neither knows that the sample repeats its periods, hence their low recall in Table 6.1.
- ``NeedlemanWunsch*`` (Alg 3) cuts the sample into candidate periods ``S[p1:p2]`` (from a member
  that heads a training pattern to the next member with the same symbol, or to the end of the
  sample when there is none) and aligns each against that pattern. Members heading no pattern
  are skipped (dropped), as the pseudo-code moves on to ``p1 + 1`` without writing them.
"""

from __future__ import annotations

import numpy as np
from numba import njit

MATCH, MISMATCH, GAP = 1, -1, -1


@njit(cache=True)
def _score(x: int, y: int) -> int:
    return MATCH if x == y else MISMATCH


@njit(cache=True)
def _fill(a: np.ndarray, b: np.ndarray, local: bool) -> np.ndarray:
    """DP matrix (len(a)+1, len(b)+1): H[i,j] = max(H[i-1,j-1]+s, H[i-1,j]+g, H[i,j-1]+g[, 0])."""
    n, m = a.shape[0], b.shape[0]
    h = np.zeros((n + 1, m + 1), dtype=np.int64)
    if not local:
        for i in range(n + 1):
            h[i, 0] = i * GAP
        for j in range(m + 1):
            h[0, j] = j * GAP
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            best = max(h[i - 1, j - 1] + _score(a[i - 1], b[j - 1]), h[i - 1, j] + GAP)
            best = max(best, h[i, j - 1] + GAP)
            h[i, j] = max(best, 0) if local else best
    return h


@njit(cache=True)
def _traceback(a: np.ndarray, b: np.ndarray, h: np.ndarray, local: bool) -> np.ndarray:
    """Indices of ``b`` paired with an identical symbol of ``a`` on the optimal path.

    The path ends in the corner (global) or at the first maximum in row-major order (local).
    Ties prefer the diagonal, then a gap in ``b``: the path is deterministic.
    """
    if local:
        flat = int(np.argmax(h))
        i, j = flat // h.shape[1], flat % h.shape[1]
    else:
        i, j = a.shape[0], b.shape[0]
    kept = np.zeros(b.shape[0], dtype=np.bool_)
    while i > 0 and j > 0:
        if local and h[i, j] == 0:
            break
        if h[i, j] == h[i - 1, j - 1] + _score(a[i - 1], b[j - 1]):
            kept[j - 1] = a[i - 1] == b[j - 1]
            i, j = i - 1, j - 1
        elif h[i, j] == h[i - 1, j] + GAP:
            i -= 1
        else:
            j -= 1
    return kept


@njit(cache=True)
def needleman_wunsch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Global alignment of ``a`` (pattern, int codes) and ``b`` (sample): (len(b),) bool kept."""
    return _traceback(a, b, _fill(a, b, False), False)


@njit(cache=True)
def smith_waterman(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Local alignment of ``a`` and ``b``: (len(b),) bool, True where ``b`` matches in the best
    local alignment."""
    return _traceback(a, b, _fill(a, b, True), True)


def nw_star(symbols: np.ndarray, pattern_syms: np.ndarray, pattern_len: np.ndarray) -> np.ndarray:
    """``NeedlemanWunsch*`` (Alg 3): (N,) bool of the kept members of the coded ``symbols``.

    ``pattern_syms`` (n_patterns, max_len) and ``pattern_len`` as in ``periodic_fitness.Coded``;
    the first pattern headed by a member's symbol is used (Alg 3 breaks at the first match).
    """
    first: dict[int, np.ndarray] = {}
    for row in range(pattern_syms.shape[0]):
        first.setdefault(int(pattern_syms[row, 0]), pattern_syms[row, : pattern_len[row]])
    kept = np.zeros(symbols.shape[0], dtype=bool)
    p1 = 0
    while p1 < symbols.shape[0]:
        pattern = first.get(int(symbols[p1]))
        if pattern is None:
            p1 += 1
            continue
        p2 = _next_occurrence(symbols, p1)
        # the closing head is the next period's start: align S[p1:p2] with the open pattern
        kept[p1:p2] = needleman_wunsch(pattern[:-1], symbols[p1:p2])
        p1 = p2
    return kept


def _next_occurrence(symbols: np.ndarray, p1: int) -> int:
    """Index of the next member equal to ``symbols[p1]``, or ``len(symbols)`` if none."""
    later = np.flatnonzero(symbols[p1 + 1 :] == symbols[p1])
    return int(p1 + 1 + later[0]) if later.size else int(symbols.shape[0])
