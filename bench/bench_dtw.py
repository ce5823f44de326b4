"""DTW speed against dtaidistance (C) and tslearn (numba), one run, same inputs.

    .venv/bin/python -m bench.bench_dtw [--repeats 5] [--markdown docs/sections/bench_dtw.md]
        [--only batched]

Cases (issue 3): 1-D 5,000 x 10,000; d = 66, 7,200 x 1,200; 64 repetitions of 90 frames x 66
against one tutor repetition (batched); the same two pairs with the warping path; the Open-End DTW
update per streamed frame against a 1,200-frame, d = 66 reference. Every library is warmed up
first (numba compilation is not timed); the timed calls are interleaved library by library, and
the median of ``--repeats`` runs is reported. Costs are squared Euclidean sums, the quantity
dtaidistance accumulates, so the printed distances must agree.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import platform
import subprocess
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from analysis.dtw import DTWOptions
from analysis.dtw import offline as dtw
from analysis.online import OpenEndAligner

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from dtaidistance import dtw as dtai
    from dtaidistance import dtw_ndim as dtai_ndim
    from tslearn import metrics as tsm

SQ = DTWOptions(cost="sqeuclidean")
NOTES = """Calls: project `analysis.dtw.distance` / `distance_batch` / `align` with squared
Euclidean cost (1-D distance: vectorised anti-diagonal sweep; d = 66: local costs as one BLAS
matrix product per block of rows, on one BLAS thread, cells where the expansion could cancel
recomputed exactly, on a second thread while the DP runs; 1-D with path: the same anti-diagonal
sweep storing one back-pointer byte per cell; d = 66 with path: the same local costs, a row DP
with back-pointers and no range tests; batch: pruned DP, local costs only for the cells whose
accumulated cost stays under the corner-to-corner path's, computed from the differences);
dtaidistance 2.5 `dtw.distance_fast`, `dtw_ndim.distance_fast`,
`dtw_ndim.distance_matrix_fast(block=..., parallel=True)` (its fastest batched form) and
`dtw.warping_path_fast`; tslearn `metrics.dtw`, `cdist_dtw`, `dtw_path`. Streaming:
`analysis.online.OpenEndAligner.push`, Euclidean cost, 300 frames per run. The machine is a
shared 2-core VM and other jobs ran at the same time (load averages above), so absolute times
vary between runs; the interleaved ratios are steadier."""


@dataclass
class Case:
    name: str
    ours: Callable[[], object]
    dtai: Callable[[], object]
    tslearn: Callable[[], object] | None
    target: float | None  # required ratio ours / dtaidistance


TARGET = 0.15  # issue 37: at most 0.15 of dtaidistance's time in every case


def model_name() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return platform.processor() or "unknown"
    line = next((s for s in out.splitlines() if s.startswith("Model name")), "Model name: ?")
    return line.split(":", 1)[1].strip()


def dtai_batch(reps: list[np.ndarray], tutor: np.ndarray) -> np.ndarray:
    """dtaidistance's best batched form: one call, distances of every repetition to the tutor."""
    series = [*reps, tutor]
    block = ((0, len(reps)), (len(reps), len(reps) + 1))
    return dtai_ndim.distance_matrix_fast(series, block=block, parallel=True, compact=True)


def cases(rng: np.random.Generator) -> tuple[list[Case], dict[str, tuple[float, float]]]:
    a, b = np.cumsum(rng.standard_normal(5000)), np.cumsum(rng.standard_normal(10000))
    x, y = rng.standard_normal((7200, 66)), rng.standard_normal((1200, 66))
    tutor = rng.standard_normal((90, 66))
    reps = [tutor + 0.5 * rng.standard_normal((90, 66)) for _ in range(64)]
    checks = {
        "1-D": (np.sqrt(dtw.distance(a, b, SQ)), dtai.distance_fast(a, b)),
        "d=66": (np.sqrt(dtw.distance(x, y, SQ)), dtai_ndim.distance_fast(x, y)),
        "batch": (
            float(np.sqrt(dtw.distance_batch(reps, tutor, SQ)).sum()),
            float(np.sum(dtai_batch(reps, tutor))),
        ),
    }
    out = [
        Case(
            "1-D 5,000 x 10,000, distance",
            lambda: dtw.distance(a, b, SQ),
            lambda: dtai.distance_fast(a, b),
            lambda: tsm.dtw(a, b),
            TARGET,
        ),
        Case(
            "d=66 7,200 x 1,200, distance",
            lambda: dtw.distance(x, y, SQ),
            lambda: dtai_ndim.distance_fast(x, y),
            lambda: tsm.dtw(x, y),
            TARGET,
        ),
        Case(
            "64 reps x 90 x 66 vs tutor, batched",
            lambda: dtw.distance_batch(reps, tutor, SQ),
            lambda: dtai_batch(reps, tutor),
            lambda: tsm.cdist_dtw(np.array(reps), tutor[None]),
            TARGET,
        ),
        Case(
            "1-D 5,000 x 10,000, with path",
            lambda: dtw.align(a, b, SQ),
            lambda: dtai.warping_path_fast(a, b),
            lambda: tsm.dtw_path(a, b),
            TARGET,
        ),
        Case(
            "d=66 7,200 x 1,200, with path",
            lambda: dtw.align(x, y, SQ),
            lambda: dtai.warping_path_fast(x, y),
            lambda: tsm.dtw_path(x, y),
            TARGET,
        ),
    ]
    return out, checks


def time_cases(
    todo: list[Case], repeats: int
) -> list[tuple[Case, list[float], list[float], list[float]]]:
    results = []
    for case in todo:
        funcs = [case.ours, case.dtai] + ([case.tslearn] if case.tslearn else [])
        for f in funcs:
            f()  # warm-up: numba compilation, caches, thread pools
        times: list[list[float]] = [[] for _ in funcs]
        for _ in range(repeats):
            for k, f in enumerate(funcs):
                t0 = time.perf_counter()
                f()
                times[k].append(time.perf_counter() - t0)
        results.append((case, times[0], times[1], times[2] if case.tslearn else []))
    return results


def push_times(rng: np.random.Generator, repeats: int) -> dict[str, float]:
    """Median over runs of the mean time per pushed frame (ms), 300 frames per run."""
    ref = rng.standard_normal((1200, 66))
    stream = ref[np.linspace(0, 1199, 300).astype(int)] + 0.1 * rng.standard_normal((300, 66))
    configs = {
        "OE-DTW": DTWOptions(),
        "WOOE-DTW (path-length weighting, 22 joint weights)": DTWOptions(
            path_length_weighting=True, weights=tuple(rng.uniform(0.5, 1.5, 22))
        ),
    }
    out = {}
    for name, opt in configs.items():
        OpenEndAligner(ref, opt).push(stream[0])  # warm-up
        runs = []
        for _ in range(repeats):
            oa = OpenEndAligner(ref, opt)
            t0 = time.perf_counter()
            for f in stream:
                oa.push(f)
            runs.append((time.perf_counter() - t0) / len(stream) * 1e3)
        out[name] = float(np.median(runs))
    return out


def table(results: list, pushes: dict[str, float], checks: dict, repeats: int) -> str:  # type: ignore[type-arg]
    lines = [
        f"Median of {repeats} interleaved runs, times in ms; ratio = project / library.",
        "",
        "| case | project | dtaidistance | ratio | target | tslearn | ratio |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for case, ours, dtai_t, ts in results:
        o, d = np.median(ours) * 1e3, np.median(dtai_t) * 1e3
        t = np.median(ts) * 1e3 if ts else float("nan")
        ok = "" if case.target is None else (" ok" if o / d <= case.target else " MISSED")
        lines.append(
            f"| {case.name} | {o:.1f} | {d:.1f} | {o / d:.3f} | <= {case.target}{ok} | "
            f"{t:.1f} | {o / t:.3f} |"
        )
    lines += [
        "",
        "| streaming update, 1,200 x 66 reference | ms per frame | target |",
        "|---|---:|---:|",
    ]
    for name, ms in pushes.items():
        lines.append(f"| {name} | {ms:.3f} | <= 0.5{' ok' if ms <= 0.5 else ' MISSED'} |")
    agree = "; ".join(f"{k} {a:.6f} vs {b:.6f}" for k, (a, b) in checks.items())
    lines += ["", f"Distances (project vs dtaidistance, must agree): {agree}.", "", NOTES]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> str:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--markdown", help="also write the section to this file")
    parser.add_argument(
        "--only", help="time only the cases whose name contains this text (e.g. batched)"
    )
    args = parser.parse_args(argv)
    rng = np.random.default_rng(20261123)
    load0 = os.getloadavg()[0]
    todo, checks = cases(rng)
    if args.only:
        todo = [c for c in todo if args.only in c.name]
    results = time_cases(todo, args.repeats)
    pushes = push_times(rng, args.repeats)
    body = table(results, pushes, checks, args.repeats)
    stamp = (
        f"{dt.date.today().isoformat()}, {model_name()}, {os.cpu_count()} cores; "
        f"load average {load0:.2f} before, {os.getloadavg()[0]:.2f} after"
    )
    only = f" --only '{args.only}'" if args.only else ""
    text = (
        "## DTW speed (bench/bench_dtw.py)\n\n"
        f"`.venv/bin/python -m bench.bench_dtw --repeats {args.repeats}{only}` - {stamp}.\n\n"
        f"{body}\n"
    )
    print(text)
    if args.markdown:
        with open(args.markdown, "w", encoding="utf-8") as fh:
            fh.write(text)
    return text


if __name__ == "__main__":
    main()
