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
session's own, and the smallest ratio of another exercise (its distance over the nearest of the
rest: at or below the margin the distance test accepts it).

The set ``others`` is the fit check as `bench.eval_mismatch` runs it: s01's reference and the
correct sessions of every other subject but the compared session's own (a clinic with confirmed
takes of other people, none of this patient's); from six takes per exercise on the check compares
with margin 1 (`analysis.pipeline.match.MatchOptions.confirmed_margin`).

    python -m bench.mismatch_references [--jobs 2] [--sets s01 s01,s02 s01,s03 s01,s04 others]
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
MARGINS = (1.0, 1.1, 1.2, 1.3)


def session_names() -> list[str]:
    return [f"{e}_{s}_{label}" for e in EXERCISES for s in SUBJECTS
            for label in ("correct", "incorrect")]  # fmt: skip


def features(name: str) -> FloatArray:
    return features_of(read(DATA / "sessions" / f"{name}.bvh.gz"))


def row(args: tuple[FloatArray, list[FloatArray]]) -> FloatArray:
    mine, library = args
    return distances(mine, library)


def references_for(session: str, subjects: list[str]) -> list[str]:
    """The reference subjects a session is compared with: ``others`` is s01 and every subject
    but the session's own."""
    if subjects != ["others"]:
        return subjects
    return [s for s in SUBJECTS if s == "s01" or s != session[4:7]]


def table(sessions: list[str], refs: list[str], dist: FloatArray, subjects: list[str]) -> str:
    """The figures for one set of reference subjects (module docstring)."""
    column = {r: k for k, r in enumerate(refs)}
    by = {n: references_for(n, subjects) for n in sessions}
    # a session that is one of its own references is not tested
    tested = [k for k, n in enumerate(sessions)
              if n[4:7] not in by[n] or not n.endswith("_correct")]  # fmt: skip
    near = np.array([
        [min(dist[k, column[f"{e}_{s}_correct"]] for s in by[sessions[k]]) for e in EXERCISES]
        for k in tested
    ])  # fmt: skip
    own = np.array([EXERCISES.index(sessions[k][:3]) for k in tested])
    others = np.array([np.delete(d, o).min() for d, o in zip(near, own, strict=True)])
    ratio = near[np.arange(len(own)), own] / others
    closest = min(d[k] / np.delete(d, k).min() for d, o in zip(near, own, strict=True)
                  for k in range(len(EXERCISES)) if k != o)  # fmt: skip
    lines = [
        f"references {'+'.join(subjects)}: {len(tested)} sessions, own exercise not the nearest "
        f"in {int((ratio > 1).sum())}, largest own ratio {ratio.max():.3f}, smallest ratio of "
        f"another exercise {closest:.3f}"
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
    every = [SUBJECTS if group == ["others"] else group for group in sets]
    refs = sorted({f"{e}_{s}_correct" for e in EXERCISES for group in every for s in group})
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
