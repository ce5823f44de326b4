"""The DTW's row-block pipeline and its helper threads: local costs of the next block are
computed on a helper thread while the DP consumes the current one.

Sharing each block's cost work between both threads (chunks taken from both ends) was tried on
2026-11-29 for the d = 66 case: no measurable gain on the shared machine (load 5-6, where the
process got about one core), so the simple pipeline stays. Computing two blocks ahead on two
helper threads was tried the same day: no gain either (the machine's scheduler shares the cores
between sessions, not threads, so under load more threads get no more processor time).
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, wait
from typing import Protocol

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.dtw import cost_blas
from analysis.dtw.cost_blas import single_threaded_blas
from analysis.dtw.frame_costs import CostInputs

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BLOCK_CELLS = 1 << 19  # cells per cost block: 4 MiB of float64, stays in cache


class RowConsumer(Protocol):
    def rows(self, C: FloatArray, i0: int, i1: int, lo: IntArray, hi: IntArray) -> None: ...


@functools.cache
def pool() -> ThreadPoolExecutor:
    """The process's DTW helper threads (one per numba thread, at least two)."""
    return ThreadPoolExecutor(max_workers=max(2, nb.get_num_threads()), thread_name_prefix="dtw")


_LOCAL = threading.local()


def _spare_blocks(rows: int, m: int) -> list[FloatArray]:
    """This thread's two cost-block buffers, kept between calls: fresh 4 MiB arrays cost a page
    fault per 4 KiB on every call (about 2,000 per call for large inputs)."""
    flat = getattr(_LOCAL, "flat", None)
    if flat is None or flat[0].size < rows * m:
        flat = [np.empty(rows * m) for _ in range(2)]
        _LOCAL.flat = flat
    return [f[: rows * m].reshape(rows, m) for f in flat]


def run_rows(ci: CostInputs, lo: IntArray, hi: IntArray, consumer: RowConsumer) -> None:
    """Fill the DP for all rows in cache-sized blocks: a helper thread computes the local costs
    of the next block while this thread runs the DP over the current one (both release the GIL)."""
    n, m = ci.x.shape[0], ci.y.shape[0]
    rows = min(n, max(4, BLOCK_CELLS // m))
    blocks = [(i0, min(n, i0 + rows)) for i0 in range(0, n, rows)]
    spare = _spare_blocks(rows, m)

    def costs(k: int) -> FloatArray:
        i0, i1 = blocks[k]
        return ci.rows(i0, i1, lo, hi, spare[k % 2])

    with single_threaded_blas(ci.uses_blas and n >= cost_blas.MIN_ROWS):
        pending = pool().submit(costs, 0) if len(blocks) > 1 else None
        try:
            for k, (i0, i1) in enumerate(blocks):
                C = pending.result() if pending is not None else costs(k)
                pending = pool().submit(costs, k + 1) if k + 1 < len(blocks) else None
                consumer.rows(C, i0, i1, lo, hi)
        finally:  # the buffers are this thread's: no helper may still write them after return
            if pending is not None:
                wait([pending])


# Below this much work (DP cells, plus local-cost work counted as one cell per 16 features) a
# second thread costs more than it saves: about 2 ms on one core.
PARALLEL_MIN_CELLS = 2_000_000


def cuts(count: int, work: int) -> list[tuple[int, int]]:
    """[0, count) in one contiguous slice per worker thread (one slice for small problems)."""
    workers = min(nb.get_num_threads(), count) if work > PARALLEL_MIN_CELLS else 1
    if workers <= 1:
        return [(0, count)]
    edges = np.linspace(0, count, workers + 1).astype(int)
    return list(zip(edges[:-1].tolist(), edges[1:].tolist(), strict=True))


def concurrently(calls: list[Callable[[], object]]) -> None:
    """Run GIL-releasing calls concurrently: all but the first in the pool, the first here."""
    futures = [pool().submit(c) for c in calls[1:]]
    calls[0]()
    for f in futures:
        f.result()
