"""Processor time of a live repetition's end as the session grows (issue 37): a UI-PRMD session
repeated to ``--seconds`` at ``--fps`` streamed through `analysis.live.LiveAligner`, with
`RepetitionJudge.score` and `RepetitionJudge.judge` timed (``time.thread_time``) at each
repetition's end; the median over ``--passes`` passes after a warm-up, for the first and the
last repetitions of the stream (the machine being shared, processor time, not wall).

    .venv/bin/python -m bench.bench_repetition_end --seconds 60 --passes 5
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

from analysis.bvh import Motion, read
from analysis.kinematics import resample
from analysis.live import LiveAligner
from analysis.live.judged import RepetitionJudge
from bench.bench_live import DATA, SESSION
from bench.eval_live import tutor_model


def repeated(motion: Motion, seconds: float, fps: float) -> Motion:
    """The session at ``fps``, played again and again up to ``seconds``."""
    one = resample(motion, fps)
    n = int(seconds * fps)
    times = -(-n // one.n_frames)
    frames = np.concatenate([one.frames] * times)[:n]
    return Motion(one.skeleton, frames, 1.0 / fps)


def _timed(method: Callable, spent: list[float]) -> Callable:
    def timed(*args: object) -> object:
        started = time.thread_time()
        try:
            return method(*args)
        finally:
            spent.append(time.thread_time() - started)

    return timed


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--fps", type=float, default=120.0)
    parser.add_argument("--passes", type=int, default=5)
    args = parser.parse_args(argv)
    model = tutor_model(DATA, "m07")
    motion = repeated(read(DATA / SESSION), args.seconds, args.fps)
    score_fn, judge_fn = RepetitionJudge.score, RepetitionJudge.judge
    runs: list[tuple[list[float], list[float]]] = []
    for _ in range(args.passes + 1):  # the first pass loads the compiled kernels
        scores: list[float] = []
        judges: list[float] = []
        RepetitionJudge.score = _timed(score_fn, scores)  # type: ignore[method-assign]
        RepetitionJudge.judge = _timed(judge_fn, judges)  # type: ignore[method-assign]
        aligner = LiveAligner(model, motion.skeleton, motion.fps)
        for values in motion.frames:
            aligner.push(values)
        aligner.finish()
        runs.append((scores, judges))
    RepetitionJudge.score, RepetitionJudge.judge = score_fn, judge_fn  # type: ignore[method-assign]
    n = min(len(s) for s, _ in runs[1:])
    print(f"{args.seconds:.0f} s at {args.fps:.0f} Hz, {n} repetitions, {args.passes} passes")
    for name, k in (("score", 0), ("judge", 1)):
        per_rep = np.median([r[k][:n] for r in runs[1:]], axis=0) * 1e3
        print(
            f"{name}: first 3 repetitions {', '.join(f'{v:.2f}' for v in per_rep[:3])} ms; "
            f"last 3 {', '.join(f'{v:.2f}' for v in per_rep[-3:])} ms; "
            f"median {np.median(per_rep):.2f} ms"
        )


if __name__ == "__main__":
    main()
