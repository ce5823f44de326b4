"""Plain, readable DTW: the specification the compiled fast paths of ``analysis.dtw`` are tested
against. Pure Python loops over full matrices; use it only for small inputs (tests, teaching).

It implements the recurrences written in ``analysis.dtw``'s module docstring literally: every cell
lists its admissible predecessors in the documented order and takes the first strict minimum.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import cast

import numpy as np
import numpy.typing as npt

from analysis.dtw.frame_costs import frame_cost, mean_frame
from analysis.dtw.offline import Alignment, DTWOptions

INF = math.inf
Cell = tuple[int, int]
Grid = list[list[float]]
Back = list[list[object]]  # predecessor per cell: a cell, (column, state) for Type V, or "start"


def _allowed(n: int, m: int, opt: DTWOptions) -> Callable[[int, int], bool]:
    """The Sakoe-Chiba band as a predicate on cells, in exact integer arithmetic."""

    def inside(i: int, j: int) -> bool:
        if not (0 <= i < n and 0 <= j < m):
            return False
        if opt.window is None or n == 1:
            return True
        if opt.open_begin or opt.open_end:
            return abs(j - i) <= opt.window
        return abs(j * (n - 1) - i * (m - 1)) <= opt.window * (n - 1)

    return inside


def _pick(
    cands: list[tuple[float, float, object]], c: float, plw: bool
) -> tuple[float, float, object]:
    """First candidate (D, L, origin) with the smallest key: D, or (D + c) / (L + 1) with PLW."""
    best = None
    best_key = INF
    for cand in cands:
        key = (cand[0] + c) / (cand[1] + 1.0) if plw else cand[0]
        if best is None or key < best_key:
            best, best_key = cand, key
    return best if best is not None else (INF, 0.0, None)


def _symmetric(C: Grid, opt: DTWOptions) -> tuple[Grid, Grid, Back]:
    n, m = len(C), len(C[0])
    inside = _allowed(n, m, opt)
    D = [[INF] * m for _ in range(n)]
    L = [[0.0] * m for _ in range(n)]
    back: Back = [[None] * m for _ in range(n)]
    for i in range(n):
        for j in range(m):
            if not inside(i, j):
                continue
            cands: list[tuple[float, float, object]] = []
            for pi, pj in ((i - 1, j - 1), (i - 1, j), (i, j - 1)):
                if inside(pi, pj):
                    cands.append((D[pi][pj], L[pi][pj], (pi, pj)))
            if i == 0 and (j == 0 or opt.open_begin):
                cands.append((0.0, 0.0, "start"))
            d, length, origin = _pick(cands, C[i][j], opt.path_length_weighting)
            D[i][j], L[i][j], back[i][j] = C[i][j] + d, length + 1.0, origin
    return D, L, back


def _typev(C: Grid, opt: DTWOptions) -> tuple[list[Grid], Back]:
    """Type V: state s = number of repeated reference frames in a row (0, 1 or 2)."""
    n, m = len(C), len(C[0])
    inside = _allowed(n, m, opt)
    D = [[[INF] * 3 for _ in range(m)] for _ in range(n)]
    back: Back = [[None] * m for _ in range(n)]
    for i in range(n):
        for j in range(m):
            if not inside(i, j):
                continue
            cands: list[tuple[float, float, object]] = []
            for k, states in ((1, (0, 1, 2)), (2, (0,)), (3, (0,))):
                if inside(i - 1, j - k):
                    cands += [(D[i - 1][j - k][s], float(i), (j - k, s)) for s in states]
            if i == 0 and (j == 0 or opt.open_begin):
                cands.append((0.0, 0.0, "start"))
            d, _, back[i][j] = _pick(cands, C[i][j], opt.path_length_weighting)
            D[i][j][0] = C[i][j] + d
            if inside(i - 1, j):
                D[i][j][1] = C[i][j] + D[i - 1][j][0]
                D[i][j][2] = C[i][j] + D[i - 1][j][1]
    return D, back


def _end_column(last: list[float], lengths: list[float], opt: DTWOptions) -> int:
    if not opt.open_end:
        return len(last) - 1
    keys = [
        d / le if opt.path_length_weighting and d < INF else d
        for d, le in zip(last, lengths, strict=True)
    ]
    best = min(keys)
    return keys.index(best) if best < INF else -1


def _trace_symmetric(back: list[list[object]], i: int, j: int) -> list[Cell]:
    path = [(i, j)]
    while isinstance(back[i][j], tuple):
        i, j = cast(Cell, back[i][j])
        path.append((i, j))
    return path[::-1]


def _trace_typev(
    D: list[list[list[float]]], back: list[list[object]], i: int, j: int
) -> list[Cell]:
    s = min(range(3), key=lambda t: (D[i][j][t], t))
    path = [(i, j)]
    while True:
        if s > 0:
            i, s = i - 1, s - 1
        elif isinstance(back[i][j], tuple):
            j, s = cast(Cell, back[i][j])
            i -= 1
        else:
            return path[::-1]
        path.append((i, j))


def _groups(path: list[Cell]) -> list[list[Cell]]:
    """Runs of cells sharing j (several i), else sharing i (several j), scanning forwards."""
    out: list[list[Cell]] = []
    k = 0
    while k < len(path):
        run = [path[k]]
        for axis in (1, 0):
            while k + len(run) < len(path) and path[k + len(run)][axis] == path[k][axis]:
                run.append(path[k + len(run)])
            if len(run) > 1:
                break
        out.append(run)
        k += len(run)
    return out


def _speed_insensitive(x: np.ndarray, y: np.ndarray, path: list[Cell], opt: DTWOptions) -> float:
    total = 0.0
    for run in _groups(path):
        a = (
            mean_frame(x[[i for i, _ in run]], opt.cost)
            if run[0][1] == run[-1][1]
            else x[run[0][0]]
        )
        b = (
            mean_frame(y[[j for _, j in run]], opt.cost)
            if run[0][0] == run[-1][0]
            else y[run[0][1]]
        )
        total += frame_cost(a, b, opt.cost, opt.weights)
    return total


def align(x: npt.ArrayLike, y: npt.ArrayLike, options: DTWOptions | None = None) -> Alignment:
    """Reference DTW with the same options and result as ``analysis.dtw.align``."""
    opt = options or DTWOptions()
    xa = np.asarray(x, dtype=np.float64)
    ya = np.asarray(y, dtype=np.float64)
    xa, ya = xa.reshape(len(xa), -1), ya.reshape(len(ya), -1)
    n, m = len(xa), len(ya)
    C = [[frame_cost(xa[i], ya[j], opt.cost, opt.weights) for j in range(m)] for i in range(n)]
    if opt.step == "type-v":
        D3, back = _typev(C, opt)
        D = [[min(cell) for cell in row] for row in D3]
        j = _end_column(D[n - 1], [float(n)] * m, opt)
        path = _trace_typev(D3, back, n - 1, j) if j >= 0 and D[n - 1][j] < INF else []
    else:
        D, L, back = _symmetric(C, opt)
        j = _end_column(D[n - 1], L[n - 1], opt)
        path = _trace_symmetric(back, n - 1, j) if j >= 0 and D[n - 1][j] < INF else []
    if not path:
        raise ValueError("no admissible warping path with these options")
    cost = _speed_insensitive(xa, ya, path, opt) if opt.speed_insensitive else D[n - 1][j]
    matrix = np.array(D) if opt.return_matrix else None
    return Alignment(cost=float(cost), path=np.array(path, dtype=np.int64), matrix=matrix)
