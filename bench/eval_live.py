"""Live sessions against the offline analysis, over every development UI-PRMD session.

For each of the 10 exercises the model is fitted from the tutor alone (subject s01's correct
session, as ``bench/eval_assessment.py``'s cold start); the patients are the development
subjects s02-s07, correct and incorrect takes (120 sessions). Each session goes through the code
path of ``python -m analysis stream --model M FILE --speed max --json-lines``
(`capture.stream.session_events`: a `LiveSession` fed every frame, then ended) and
through the offline analysis (`analysis.pipeline.analyse`). Per session:

- repetition count: the live summary's count against the offline analysis's repetitions;
- tutor playback: the live ``tutor_frame`` of every frame inside an offline repetition against
  offline DTW of that repetition with the tutor repetition the live aligner follows (same
  quaternion features, joint weights and side as offline), |live - offline| in frames at 30 fps;
- processing per frame: each position event's ``latency_ms`` (the aligner's time for the frame).

    .venv/bin/python -m bench.eval_live [--jobs 2] [--exercises m01,m02]
        [--markdown docs/sections/eval_live.md]
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import platform
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from analysis.bvh import read
from analysis.dtw import align
from analysis.dtw.metrics import offline_mapping
from analysis.live import LiveAligner
from analysis.pipeline import analyse, build_model
from analysis.pipeline.model import FittedModel
from capture.sources import file_source
from capture.stream import session_events

DATA = Path(__file__).resolve().parents[1] / "data" / "ui-prmd"


def machine() -> str:
    """The processor model, core count and memory, e.g. "2-core AMD EPYC 7B13, 24 GiB"."""
    model = platform.machine()
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("model name"):
            model = line.split(":", 1)[1].strip()
            break
    memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    return f"{os.cpu_count()}-core {model}, {memory:.0f} GiB"


EXERCISES = [f"m{k:02d}" for k in range(1, 11)]
SUBJECTS = [f"s{k:02d}" for k in range(2, 8)]
LABELS = ("correct", "incorrect")


@dataclass(frozen=True)
class SessionResult:
    name: str
    live: int
    offline: int
    deviations: np.ndarray  # |live - offline DTW| tutor frame, per frame in offline repetitions
    latencies_ms: np.ndarray  # per frame, wall time
    cpu_ms: np.ndarray  # per frame, processor time of the aligner's thread
    seconds: float
    tips_equal: int  # repetitions whose first tip (or none) is the offline analysis's
    tips_compared: int  # repetitions compared (the first min(live, offline) of each)


def tutor_model(data: Path, exercise: str) -> FittedModel:
    name = f"sessions/{exercise}_s01_correct.bvh.gz"
    for line in (data / "landmarks.csv").read_text().splitlines():
        if line.startswith(name):
            _, frames, types = line.split(",")
            ints = [int(v) for v in frames.split(";")], [int(v) for v in types.split(";")]
            return build_model(read(data / name), *ints)
    raise LookupError(name)


def playback_deviation(
    model: FittedModel, path: Path, tutor_frames: np.ndarray, offline: object
) -> np.ndarray:
    """|live tutor frame - offline DTW tutor frame| for the frames of the offline repetitions."""
    motion = read(path)
    aligner = LiveAligner(model, motion.skeleton, motion.fps)
    direct, mirror = aligner.features_of(motion.frames)
    q = mirror if offline.mirrored else direct  # type: ignore[attr-defined]
    tutor, options = aligner.tutor_features, aligner.dtw_options
    out = []
    for rep in offline.repetitions:  # type: ignore[attr-defined]
        piece = q[rep.start : rep.end + 1]
        if len(piece) < 2:
            continue
        mapped = aligner.tutor_start + offline_mapping(
            align(piece, tutor, options).path, len(piece)
        )
        live = tutor_frames[rep.start : rep.end + 1]
        out.append(np.abs(live - mapped))
    return np.concatenate(out) if out else np.zeros(0)


def run_session(model: FittedModel, path: Path) -> SessionResult:
    started = time.perf_counter()
    events = list(session_events(model, file_source(str(path), None)))
    seconds = time.perf_counter() - started
    positions = [e for e in events if e["event"] == "position"]
    tutor_frames = np.full(read(path).n_frames, np.nan)
    for e in positions:
        tutor_frames[e["frame"]] = e["tutor_frame"]
    offline = analyse(read(path), model).summary
    deviation = playback_deviation(model, path, tutor_frames, offline)
    live_tips = [r["guidance"][:1] for r in events if r["event"] == "repetition"]
    pairs = list(zip(live_tips, offline.repetitions, strict=False))
    same = sum([g["type"] for g in tip] == [g.type for g in rep.guidance[:1]] for tip, rep in pairs)
    return SessionResult(
        name=path.name,
        live=int(events[-1]["repetitions"]),
        offline=len(offline.repetitions),
        deviations=deviation[np.isfinite(deviation)],
        latencies_ms=np.array([e["latency_ms"] for e in positions]),
        cpu_ms=np.array([e["cpu_ms"] for e in positions]),
        seconds=seconds,
        tips_equal=same,
        tips_compared=len(pairs),
    )


def run_exercise(exercise: str, data: Path) -> list[SessionResult]:
    """One exercise's 12 development sessions (a worker process with ``--jobs``)."""
    model = tutor_model(data, exercise)
    warm = data / f"reps/{exercise}_s01_e01.bvh.gz"  # compiled kernels load once per process
    list(session_events(model, file_source(str(warm), None)))
    out = []
    for subject in SUBJECTS:
        for label in LABELS:
            r = run_session(model, data / f"sessions/{exercise}_{subject}_{label}.bvh.gz")
            flag = "" if r.live == r.offline else "  <-- differs"
            print(f"{exercise} {r.name}: live {r.live}, offline {r.offline}{flag}", flush=True)
            out.append(r)
    return out


def table(results: dict[str, list[SessionResult]]) -> tuple[str, dict[str, float]]:
    lines = [
        "| exercise | sessions | live count = offline | within ±1 | median playback "
        "deviation (frames) | p95 processor time per frame (ms) | p95 wall time per frame (ms) |",
        "|---|---|---|---|---|---|---|",
    ]
    for ex, rs in results.items():
        equal = sum(r.live == r.offline for r in rs)
        near = sum(abs(r.live - r.offline) <= 1 for r in rs)
        dev = float(np.median(np.concatenate([r.deviations for r in rs])))
        p95 = float(np.percentile(np.concatenate([r.latencies_ms for r in rs]), 95))
        cpu = float(np.percentile(np.concatenate([r.cpu_ms for r in rs]), 95))
        lines.append(f"| {ex} | {len(rs)} | {equal} | {near} | {dev:.1f} | {cpu:.3f} | {p95:.3f} |")
    every = [r for rs in results.values() for r in rs]
    totals = {
        "sessions": float(len(every)),
        "equal": sum(r.live == r.offline for r in every) / max(len(every), 1),
        "near": sum(abs(r.live - r.offline) <= 1 for r in every) / max(len(every), 1),
        "deviation": float(np.median(np.concatenate([r.deviations for r in every]))),
        "p95": float(np.percentile(np.concatenate([r.cpu_ms for r in every]), 95)),
        "p50": float(np.percentile(np.concatenate([r.cpu_ms for r in every]), 50)),
        "wall95": float(np.percentile(np.concatenate([r.latencies_ms for r in every]), 95)),
        "wall50": float(np.percentile(np.concatenate([r.latencies_ms for r in every]), 50)),
        "tips_equal": float(sum(r.tips_equal for r in every)),
        "tips_compared": float(sum(r.tips_compared for r in every)),
    }
    lines.append(
        f"| **all** | {len(every)} | {totals['equal']:.1%} | {totals['near']:.1%} | "
        f"{totals['deviation']:.1f} | {totals['p95']:.3f} | {totals['wall95']:.3f} |"
    )
    return "\n".join(lines), totals


def verdicts(t: dict[str, float]) -> str:
    checks = [
        (f"repetition count equal to offline on ≥ 98 % of sessions: {t['equal']:.1%}",
         t["equal"] >= 0.98),
        (f"median playback deviation ≤ 10 frames: {t['deviation']:.1f}", t["deviation"] <= 10),
        (f"p95 processing per frame ≤ 2 ms: {t['p95']:.3f} ms of processor time (p50 "
         f"{t['p50']:.3f} ms); wall time, which also counts waiting for a processor on the "
         f"shared machine: p95 {t['wall95']:.3f} ms, p50 {t['wall50']:.3f} ms", t["p95"] <= 2.0),
    ]  # fmt: skip
    return "\n".join(f"- {'met' if ok else 'NOT met'}: {text}" for text, ok in checks)


def guidance_line(t: dict[str, float]) -> str:
    """How often the live guidance is what the recording's page says afterwards."""
    share = t["tips_equal"] / max(t["tips_compared"], 1.0)
    return (
        "Guidance: the first tip of a live repetition (or none) is the offline analysis's for "
        f"the same repetition on {t['tips_equal']:.0f} of {t['tips_compared']:.0f} repetitions "
        f"({share:.1%}). Both apply the same rule (`analysis.pipeline.gestures.guidance`); "
        "they differ where the live repetition ends at the trough after the movement and the "
        "offline one runs on to the next start (a tempo tip), or where the offline analysis "
        "pairs the repetition with another tutor repetition by its key poses."
    )


def main(argv: list[str] | None = None) -> str:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--exercises", default=",".join(EXERCISES))
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--markdown", type=Path, help="write the section to this file")
    args = parser.parse_args(argv)
    exercises = args.exercises.split(",")
    started = time.perf_counter()
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        runs = pool.map(run_exercise, exercises, [args.data] * len(exercises))
        results = dict(zip(exercises, runs, strict=True))
    body, totals = table(results)
    differs = [
        f"{r.name} (live {r.live}, offline {r.offline})"
        for rs in results.values()
        for r in rs
        if r.live != r.offline
    ]
    text = "\n".join([
        "## Live sessions against the offline analysis",
        "",
        f"Measured {dt.date.today().isoformat()} on the project's VM ({machine()}, Python "
        f"{platform.python_version()}), load average "
        f"{', '.join(f'{v:.1f}' for v in os.getloadavg())} after the run, "
        f"{args.jobs} worker processes, {time.perf_counter() - started:.0f} s.",
        "Command: `.venv/bin/python -m bench.eval_live --jobs "
        f"{args.jobs} --markdown docs/sections/eval_live.md`.",
        "",
        "Every development UI-PRMD session (subjects s02–s07, correct and incorrect takes, "
        "10 exercises) streamed through the code path of `python -m analysis stream --model M "
        "FILE --speed max --json-lines`, the model fitted from subject s01's correct take alone. "
        "Playback deviation: the live tutor frame of every frame inside an offline repetition "
        "against offline DTW of that repetition with the tutor repetition (frames at 30 fps). "
        "Per frame: the live aligner's processing of each frame, as processor time of its "
        "thread (what the frame costs) and as wall time.",
        "",
        body,
        "",
        verdicts(totals),
        "",
        "Sessions whose live count differs: " + ("; ".join(differs) or "none") + ".",
        "",
        guidance_line(totals),
    ])  # fmt: skip
    print(text)
    if args.markdown:
        args.markdown.write_text(text + "\n", encoding="utf-8")
    return text


if __name__ == "__main__":
    main()
