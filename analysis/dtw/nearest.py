"""For each of many queries, the closest of a few references by closed Euclidean DTW, in one
compiled call: what `align` with default options gives query by query and reference by
reference, with the same bits.

Repetition scoring aligns every repetition of a recording with every tutor repetition (a 60 s
recording: 22 × 11 alignments of about 80 × 70 frames). Each `align` call spends more on its
set-up (validation, `CostInputs`, band limits, working arrays, the helper thread's hand-off)
than on its dynamic programme; here the set-up is done once for all pairs.

Bits: the local costs are computed as `CostInputs.rows` computes them for one unbanded
alignment. A query of at least `cost_blas.MIN_ROWS` rows with at least `cost_blas.MIN_DIM`
features gets its block from a matrix product of exactly the shape `align` asks BLAS for (one
call per pair, the query rows against the whole reference: a product's rounding may depend on
its shape) and `cost_blas.finish`; any other from the compiled direct loops (`cost_rows`). The
dynamic programme and back-tracking are the kernels `align` runs (`kernels.rows_path`,
`kernels.backtrack_symmetric`), and the closest reference is the first with the smallest mean
cost per path cell, compared as `cost / len(path)` in float64.
"""

from __future__ import annotations

from collections.abc import Sequence

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.dtw import cost_blas
from analysis.dtw import kernels as kern
from analysis.dtw.frame_costs import MODE_EUC, as_frames, cost_rows
from analysis.dtw.offline import DIAGONAL_MAX_DIM, align
from analysis.dtw.row_blocks import BLOCK_CELLS

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
INF = np.inf


def _offsets(lengths: Sequence[int]) -> IntArray:
    """Start of each item and the end of the last (K + 1,) in a flat layout."""
    return np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)


def _products(
    queries: Sequence[FloatArray], refs_t: Sequence[FloatArray], blas_rows: int
) -> tuple[FloatArray, IntArray]:
    """Every query's (n, m) product with every reference, one BLAS call per pair as `align`
    makes it, flat in query-major order (empty for queries of fewer than ``blas_rows`` rows),
    and where each pair's block starts (B × K + 1,)."""
    sizes = [len(q) * rt.shape[1] if len(q) >= blas_rows else 0 for q in queries for rt in refs_t]
    starts = _offsets(sizes)
    flat = np.empty(int(starts[-1]))
    with cost_blas.single_threaded_blas():
        for b, q in enumerate(queries):
            if len(q) < blas_rows:
                continue
            for k, rt in enumerate(refs_t):
                at = int(starts[b * len(refs_t) + k])
                block = flat[at : at + len(q) * rt.shape[1]].reshape(len(q), rt.shape[1])
                np.matmul(q, rt, out=block)
    return flat, starts


@nb.njit(cache=True, nogil=True)
def _pair_costs(  # noqa: PLR0917 - numba functions take positional arguments only
    x: FloatArray, y: FloatArray, yt: FloatArray, ynorm: FloatArray, G: FloatArray,
    use_blas: bool, lo: IntArray, hi: IntArray, out: FloatArray,
) -> None:  # fmt: skip
    """Euclidean local costs (n, m) of query x against reference y, as `CostInputs.rows`."""
    if use_blas:
        cost_blas.finish(G, x, x, y, ynorm, np.zeros(0), 0, True, out)
    else:
        cost_rows(MODE_EUC, x, yt, np.zeros(0), 0, 0, x.shape[0], lo, hi, out)


@nb.njit(cache=True, nogil=True)
def _closest_all(  # noqa: PLR0917
    X: FloatArray, xoff: IntArray, Y: FloatArray, YT: FloatArray, yoff: IntArray,
    ynorm: FloatArray, G: FloatArray, goff: IntArray, blas_rows: int,
    best: IntArray, paths: IntArray, plens: IntArray, poff: IntArray,
) -> None:  # fmt: skip
    """For each query b (rows xoff[b]:xoff[b+1] of X), the first reference k (rows
    yoff[k]:yoff[k+1] of Y, columns of YT) with the smallest cost / path length, into best[b],
    and that alignment's path, reversed, into paths[poff[b]:] (its length in plens[b])."""
    K = yoff.size - 1
    m_max = 0
    for k in range(K):
        m_max = max(m_max, yoff[k + 1] - yoff[k])
    for b in range(xoff.size - 1):
        x = X[xoff[b] : xoff[b + 1]]
        n = x.shape[0]
        # flat buffers, each pair's (n, m) view contiguous (the kernels' loops vectorise)
        C, dirs = np.empty(n * m_max), np.empty(n * m_max, np.uint8)
        D2, out = np.empty(2 * m_max), np.empty((n + m_max, 2), np.int64)
        lo = np.zeros(n, np.int64)
        best_mean, best[b] = INF, -1
        for k in range(K):
            y0, y1 = yoff[k], yoff[k + 1]
            m = y1 - y0
            hi = np.full(n, m - 1, np.int64)
            g0 = goff[b * K + k]
            G_pair = G[g0 : g0 + n * m].reshape((n, m)) if n >= blas_rows else G[:0].reshape((0, m))
            Ck, dk = C[: n * m].reshape((n, m)), dirs[: n * m].reshape((n, m))
            Dk = D2[: 2 * m].reshape((2, m))
            _pair_costs(x, Y[y0:y1], YT[:, y0:y1], ynorm[y0:y1], G_pair, n >= blas_rows, lo, hi, Ck)
            Dk[:] = INF
            kern.rows_path(Ck, 0, n, lo, hi, Dk, dk)
            cost = Dk[(n - 1) & 1, m - 1]
            length = kern.backtrack_symmetric(dk, n - 1, m - 1, out[: n + m])
            mean = cost / length
            if best[b] < 0 or mean < best_mean:
                best_mean, best[b], plens[b] = mean, k, length
                paths[poff[b] : poff[b] + length] = out[:length]


def _closest_by_align(x: FloatArray, ys: Sequence[FloatArray]) -> tuple[int, IntArray]:
    """`closest_paths` for one query, one `align` call per reference."""
    best: tuple[float, IntArray, int] | None = None
    for k, y in enumerate(ys):
        result = align(x, y)
        mean = result.cost / len(result.path)
        if best is None or mean < best[0]:
            best = (mean, result.path, k)
    assert best is not None
    return best[2], best[1]


def closest_paths(
    queries: Sequence[npt.ArrayLike], references: Sequence[npt.ArrayLike]
) -> list[tuple[int, IntArray]]:
    """For each query (n_b, d), the index of the closest reference (m_k, d) by closed Euclidean
    DTW (smallest cost per path cell, the first on ties) and that alignment's path (K, 2) of
    (query frame, reference frame): ``align(query, reference)`` for every pair, compared as
    ``cost / len(path)``, without its per-call set-up."""
    xs = [as_frames(q, "x") for q in queries]
    ys = [as_frames(r, "y") for r in references]
    if not xs or not ys or len({a.shape[1] for a in xs + ys}) != 1:
        raise ValueError("queries and references need one feature count and at least one each")
    few_features = xs[0].shape[1] <= DIAGONAL_MAX_DIM  # `align` sweeps anti-diagonals then
    if few_features or max(map(len, xs)) * max(map(len, ys)) > BLOCK_CELLS:  # or splits rows
        return [_closest_by_align(x, ys) for x in xs]
    refs_t = [np.ascontiguousarray(y.T) for y in ys]
    # queries with fewer rows (or any query with few features) get the direct costs, as in align
    blas_rows = cost_blas.MIN_ROWS if xs[0].shape[1] >= cost_blas.MIN_DIM else BLOCK_CELLS + 1
    G, goff = _products(xs, refs_t, blas_rows)
    # each reference's squared norms as `CostInputs` computes them, for the expansion
    ynorm = np.concatenate([np.einsum("jk,jk->j", y, y) for y in ys])
    xoff, yoff = _offsets([len(x) for x in xs]), _offsets([len(y) for y in ys])
    m_max = max(len(y) for y in ys)
    poff = _offsets([len(x) + m_max for x in xs])
    best, plens = np.empty(len(xs), np.int64), np.zeros(len(xs), np.int64)
    paths = np.empty((int(poff[-1]), 2), np.int64)
    Y = np.concatenate(ys)
    _closest_all(np.concatenate(xs), xoff, Y, np.ascontiguousarray(Y.T), yoff, ynorm, G, goff,
                 blas_rows, best, paths, plens, poff)  # fmt: skip
    return [
        (int(best[b]), np.ascontiguousarray(paths[poff[b] : poff[b] + plens[b]][::-1]))
        for b in range(len(xs))
    ]
