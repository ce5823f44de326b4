"""Per-stage time of the analysis pipeline.

1. A 60 s, 120 fps, 31-joint recording: a UI-PRMD session resampled to 120 fps, repeated to 60 s,
   with 9 extra hand/foot joints (so 31 joints) on both the tutor and the recording; the model is
   built from the same-rig tutor. Median of 5 runs after one warm-up (numba compiles once); each
   run analyses a fresh copy of the recording, as a worker gets a new upload (nothing computed
   for an earlier run's motion can help). The model build (from the 120 fps tutor) is timed too
   (median of ``--runs`` builds), and the first build and first analysis of the process are
   printed apart (cold: numba's kernels loaded from its cache, or compiled when the cache is
   stale). ``--clock cpu`` times with the process's processor time instead of the wall clock
   (steadier on a machine shared with other jobs), the stage table too.
2. Every UI-PRMD session against its exercise's s01-correct tutor (cold-start models); left out
   with ``--no-sessions``.

    python -m bench.bench_pipeline [--data data/ui-prmd] [--runs 5] [--clock cpu] [--no-sessions]
"""

from __future__ import annotations

import argparse
import csv
import os
import platform
import time
import types
from collections.abc import Callable
from pathlib import Path

import numpy as np

import analysis.pipeline.run as pipeline_run
from analysis.bvh import Motion, Skeleton, read
from analysis.kinematics import resample
from analysis.pipeline import analyse, build_model

EXTRA = ("LeftThumb", "LeftIndex", "LeftPinky", "RightThumb", "RightIndex", "RightPinky",
         "LeftHeel", "RightHeel", "Jaw")  # fmt: skip
EXTRA_PARENTS = ("LeftHand", "LeftHand", "LeftHand", "RightHand", "RightHand", "RightHand",
                 "LeftFoot", "RightFoot", "Head")  # fmt: skip


def with_extra_joints(motion: Motion) -> Motion:
    """The motion with 9 more joints (3 rotation channels each, held still): 22 → 31 joints."""
    sk = motion.skeleton
    parents = [sk.names.index(p) for p in EXTRA_PARENTS]
    skeleton = Skeleton(
        names=(*sk.names, *EXTRA),
        parents=np.concatenate((sk.parents, parents)).astype(np.int64),
        offsets=np.concatenate((sk.offsets, np.tile([0.0, -4.0, 2.0], (len(EXTRA), 1)))),
        channels=(*sk.channels, *(("Zrotation", "Xrotation", "Yrotation"),) * len(EXTRA)),
        end_site_parents=sk.end_site_parents,
        end_site_offsets=sk.end_site_offsets,
    )
    zeros = np.zeros((motion.n_frames, 3 * len(EXTRA)))
    return Motion(skeleton, np.hstack((motion.frames, zeros)), motion.frame_time)


def fresh(motion: Motion) -> Motion:
    """A new Motion with the same frames (a new upload: no earlier run's work attached to it)."""
    return motion.with_frames(motion.frames.copy())


def landmarks(data: Path, name: str) -> tuple[list[int], list[int]]:
    with open(data / "landmarks.csv") as handle:
        for row in csv.DictReader(handle):
            if row["file"] == name:
                return [int(v) for v in row["frames"].split(";")], [
                    int(v) for v in row["types"].split(";")
                ]
    raise LookupError(name)


def long_recording_table(data: Path, runs: int, clock: Callable[[], float]) -> None:
    tutor_name = "sessions/m01_s01_correct.bvh.gz"
    frames, types = landmarks(data, tutor_name)
    tutor = with_extra_joints(resample(read(data / tutor_name), 120.0))
    marks = [min(4 * f, tutor.n_frames - 1) for f in frames]
    start = clock()
    model = build_model(fresh(tutor), marks, types)
    first_build = clock() - start
    builds = []
    for _ in range(runs):
        start = clock()
        model = build_model(fresh(tutor), marks, types)
        builds.append(clock() - start)
    take = resample(read(data / "sessions/m01_s03_correct.bvh.gz"), 120.0)
    repeats = int(np.ceil(7200 / take.n_frames))
    recording = with_extra_joints(take.with_frames(np.tile(take.frames, (repeats, 1))[:7200]))
    start = clock()
    analyse(fresh(recording), model)  # warm-up: the numba kernels the build did not load
    first_analysis = clock() - start
    totals, stages = [], []
    for _ in range(runs):
        upload = fresh(recording)
        start = clock()
        result = analyse(upload, model).to_json()
        totals.append(clock() - start)
        stages.append(result["timings_ms"])
    print(f"\n60 s × 120 fps × {len(recording.skeleton.names)} joints "
          f"({recording.n_frames} frames), median of {runs}\n")  # fmt: skip
    print("| stage | ms |\n|---|---|")
    for stage in stages[0]:
        print(f"| {stage} | {np.median([s[stage] for s in stages]):.1f} |")
    kind = "processor time" if clock is time.process_time else "wall"
    print(f"| **total ({kind})** | {1000 * np.median(totals):.1f} |")
    print(f"\nModel build from the {tutor.n_frames}-frame tutor ({kind}): median "
          f"{np.median(builds):.3f} s; the process's first build {first_build:.3f} s and "
          f"first analysis {first_analysis:.3f} s")  # fmt: skip


def sessions_table(data: Path) -> None:
    models = {}
    times: dict[str, list[float]] = {}
    for path in sorted((data / "sessions").glob("*.bvh.gz")):
        exercise = path.name[:3]
        if exercise not in models:
            name = f"sessions/{exercise}_s01_correct.bvh.gz"
            models[exercise] = build_model(read(data / name), *landmarks(data, name))
        motion = read(path)
        start = time.perf_counter()
        analyse(motion, models[exercise])
        times.setdefault(exercise, []).append(time.perf_counter() - start)
    print("\nEvery UI-PRMD session (30 fps, 22 joints), seconds per session\n")
    print("| exercise | sessions | median s | max s |\n|---|---|---|---|")
    for exercise, values in times.items():
        print(f"| {exercise} | {len(values)} | {np.median(values):.3f} | {max(values):.3f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=Path("data/ui-prmd"))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--clock", choices=("wall", "cpu"), default="wall")
    parser.add_argument("--no-sessions", action="store_true", help="the long recording only")
    args = parser.parse_args()
    threads = os.environ.get("NUMBA_NUM_THREADS", "default")
    print(f"Pipeline benchmark, {time.strftime('%Y-%m-%d')}, {platform.machine()}, "
          f"{os.cpu_count()} cores; numba threads {threads}")  # fmt: skip
    clock = time.process_time if args.clock == "cpu" else time.perf_counter
    if args.clock == "cpu":  # the stage timer reads `time.perf_counter` of the pipeline's module
        pipeline_run.time = types.SimpleNamespace(perf_counter=time.process_time)  # type: ignore[assignment]
    long_recording_table(args.data, args.runs, clock)
    if not args.no_sessions:
        sessions_table(args.data)


if __name__ == "__main__":
    main()
