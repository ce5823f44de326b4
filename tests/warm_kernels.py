"""Fills the analysis' compiled-kernel cache before `make test` starts its processes.

The analysis' numba kernels are compiled at their first call and kept in `__pycache__`
(``cache=True``). On a fresh clone that cache is empty, and at the start of `make test` every
xdist worker, every site and Celery worker a browser test starts and every `python -m
analysis` a test runs would compile the same kernels at once, each its own copy: 10–12 s of
processor time per process (docs/PERFORMANCE.md, "The test suite's time"). Running the
analysis' main paths once here, in one process, leaves the compiled kernels for all of them.

    .venv/bin/python -m tests.warm_kernels
"""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from analysis.__main__ import main as analysis_cli
from analysis.bvh import read
from analysis.dtw.frame_costs import COST_KINDS
from analysis.dtw.offline import DTWOptions, align, distance
from analysis.live import LiveAligner
from analysis.pipeline.model import load_model

DATA = Path(__file__).resolve().parents[1] / "data" / "ui-prmd"
TUTOR = "sessions/m07_s01_correct"
TRAINING = "sessions/m07_s02_incorrect.bvh.gz|0;40;80|1;2;1|incorrect"
PATIENT = "sessions/m07_s03_incorrect.bvh.gz"


def tutor_marks() -> tuple[str, str]:
    for line in (DATA / "landmarks.csv").read_text().splitlines():
        if line.startswith(TUTOR):
            _, frames, types = line.split(",")
            return frames, types
    raise LookupError(TUTOR)


def run_cli(args: list[str]) -> None:
    with contextlib.redirect_stdout(io.StringIO()):
        code = analysis_cli(args)
    if code != 0:
        raise SystemExit(f"warming the kernels: `python -m analysis {args[0]}` exited {code}")


def offline_and_live(folder: Path) -> None:
    """Model build, offline analysis and a live session: the pipeline's kernels."""
    model_path = folder / "m07.model"
    frames, types = tutor_marks()
    tutor = str(DATA / f"{TUTOR}.bvh.gz")
    training = str(DATA / TRAINING)
    run_cli(["build-model", "--tutor", tutor, "--landmarks", frames, "--types", types,
             "--train", training, "--out", str(model_path)])  # fmt: skip
    run_cli(["analyse", "--model", str(model_path), str(DATA / PATIENT)])
    motion = read(DATA / PATIENT)
    with model_path.open("rb") as stream:
        model = load_model(stream)
    aligner = LiveAligner(model, motion.skeleton, motion.fps)
    for values in motion.frames[:600]:
        aligner.push(values)
    aligner.finish()


def time_warping() -> None:
    """Every frame cost, with and without a band and speed-insensitive costs (as the DTW tests
    call them)."""
    rng = np.random.default_rng(0)
    for kind in COST_KINDS:
        width = 8 if kind in ("quaternion", "geodesic") else 3
        x, y = rng.normal(size=(40, width)), rng.normal(size=(35, width))
        for options in (
            DTWOptions(cost=kind),
            DTWOptions(cost=kind, window=5),
            DTWOptions(cost=kind, speed_insensitive=True),
        ):
            align(x, y, options)
            distance(x, y, options)


def main() -> int:
    started = time.process_time()
    with tempfile.TemporaryDirectory() as folder:
        offline_and_live(Path(folder))
    time_warping()
    print(f"compiled kernels ready ({time.process_time() - started:.1f} s of processor time)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
