"""Would more reference takes per exercise separate the neighbouring exercises (issue 35, item 6)?

The fit check (`analysis.pipeline.match`) compares a recording with one reference take per
exercise. With one take, a few development sessions are nearer to another exercise's reference
than to their own (sit to stand nearer the deep squat, shoulder abduction nearer scaption, the
inline lunge nearer the side lunge), so any margin that keeps them also accepts neighbouring
exercises' sessions, and the exercise named for a move can be the wrong one.

This measures, with the check's own distance (`match.distances`: paper 002's DTW on the 17
body-part distances, the nearer of the take and its mirror image), what happens when each exercise
is represented by the correct sessions of several subjects and a recording's distance to an
exercise is its distance to the nearest of them. For each set of reference subjects, every UI-PRMD
development session that is not a reference (s01–s07, correct and incorrect) is compared with the
ten exercises; per margin it prints the sessions whose own exercise is not the nearest, the
largest own-exercise ratio (own distance over the nearest other exercise's), the sessions of the
right exercise the margin refuses, the pairs of a session and another exercise the distance test
accepts, and the refusals whose nearest exercise (the one a move would follow) is not the
session's own.

    python -m bench.mismatch_references [--jobs 2] [--sets s01 s01,s02 s01,s03 s01,s04]
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import time

import numpy as np
import numpy.typing as npt

from analysis.bvh import read
from analysis.pipeline.match import distances, features_of
from bench.eval_mismatch import DATA, EXERCISES, SUBJECTS

FloatArray = npt.NDArray[np.float64]
MARGINS = (1.1, 1.2, 1.3)


def session_names() -> list[str]:
    return [f"{e}_{s}_{label}" for e in EXERCISES for s in SUBJECTS
            for label in ("correct", "incorrect")]  # fmt: skip


def features(name: str) -> FloatArray:
    return features_of(read(DATA / "sessions" / f"{name}.bvh.gz"))


def row(args: tuple[FloatArray, list[FloatArray]]) -> FloatArray:
    mine, library = args
    return distances(mine, library)


def table(sessions: list[str], refs: list[str], dist: FloatArray, subjects: list[str]) -> str:
    """The figures for one set of reference subjects (module docstring)."""
    column = {r: k for k, r in enumerate(refs)}
    taken = {f"{e}_{s}_correct" for e in EXERCISES for s in subjects}
    tested = [k for k, n in enumerate(sessions) if n not in taken]
    near = np.array([
        [min(dist[k, column[f"{e}_{s}_correct"]] for s in subjects) for e in EXERCISES]
        for k in tested
    ])  # fmt: skip
    own = np.array([EXERCISES.index(sessions[k][:3]) for k in tested])
    others = np.array([np.delete(d, o).min() for d, o in zip(near, own, strict=True)])
    ratio = near[np.arange(len(own)), own] / others
    lines = [
        f"references {'+'.join(subjects)}: {len(tested)} sessions, own exercise not the nearest "
        f"in {int((ratio > 1).sum())}, largest own ratio {ratio.max():.3f}"
    ]
    for margin in MARGINS:
        accepted = wrong_first = 0
        for d, o in zip(near, own, strict=True):
            for k in range(len(EXERCISES)):
                if k == o:
                    continue
                if d[k] <= margin * np.delete(d, k).min():
                    accepted += 1
                elif int(np.argmin(d)) != o:
                    wrong_first += 1
        lines.append(
            f"  margin {margin}: own refused {int((ratio > margin).sum())}, other exercises "
            f"accepted {accepted} of {len(tested) * (len(EXERCISES) - 1)}, refusals naming "
            f"another exercise first {wrong_first}"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--sets", nargs="*", default=["s01", "s01,s02", "s01,s03", "s01,s04"])
    args = parser.parse_args()
    start = time.perf_counter()
    sets = [s.split(",") for s in args.sets]
    sessions = session_names()
    refs = sorted({f"{e}_{s}_correct" for e in EXERCISES for group in sets for s in group})
    with multiprocessing.get_context("fork").Pool(args.jobs) as pool:
        found = dict(zip(sessions, pool.map(features, sessions, chunksize=4), strict=True))
        library = [found[r] for r in refs]
        dist = np.array(pool.map(row, [(found[n], library) for n in sessions], chunksize=4))
    for subjects in sets:
        print(table(sessions, refs, dist, subjects))
    print(
        f"{len(sessions)} sessions × {len(refs)} reference takes in "
        f"{time.perf_counter() - start:.0f} s, load average {os.getloadavg()[0]:.1f}"
    )


if __name__ == "__main__":
    main()
