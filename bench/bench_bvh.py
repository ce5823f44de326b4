"""Reading BVH and computing world positions: this project against the PyPI packages ``bvh`` and
``bvhio``, in one run, on the same uncompressed files.

Data: every UI-PRMD session (decompressed into a temporary directory first, outside the timing)
read as one corpus, and a synthetic 60 s × 120 fps × 31-joint file written to the same directory.
Timed per engine, for the whole corpus or the one file:

- this project: ``analysis.bvh.read(path)`` (reading alone) and ``read`` + ``kinematics.positions``;
- ``bvh``: ``Bvh(text)`` on the file's text plus ``np.array(frames, dtype=float)`` (it has no
  forward kinematics, so this is less work than ours);
- ``bvhio``: ``readAsHierarchy(path)``, which parses and builds every joint's per-frame transform.

Each figure is the median of several runs (fewer for bvhio, which takes minutes per corpus run);
MB/s are of uncompressed BVH text. Usage::

    .venv/bin/python -m bench.bench_bvh [--data data/ui-prmd] [--runs 5] [--bvh-runs 5]
                                        [--bvhio-runs 3] [--files N] [--markdown PATH]
"""

from __future__ import annotations

import argparse
import datetime
import gzip
import importlib.metadata
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from analysis.bvh import Motion, Skeleton, read, write
from analysis.kinematics import positions

TARGETS = {
    "vs_bvh": 10.0,
    "vs_bvh_cpu": 20.0,  # issue 37: read + positions against bvh, processor time
    "vs_bvhio": 100.0,
    "read_mb_s": 60.0,
    "positions_ms": 30.0,
}
ROTATION = ("Zrotation", "Xrotation", "Yrotation")
# A UI-PRMD-like (Kinect-style, y up, cm) body with hands, thumbs, fingers and toes: 31 joints
# in file (pre-)order as (name, parent, offset).
BODY_31 = [
    ("Hips", "", (0, 95, 0)), ("Spine", "Hips", (0, 10, 0)), ("Spine1", "Spine", (0, 12, 0)),
    ("Chest", "Spine1", (0, 12, 0)), ("Neck", "Chest", (0, 14, 0)), ("Head", "Neck", (0, 8, 0)),
    ("HeadTip", "Head", (0, 15, 0)), ("LeftShoulder", "Chest", (4, 10, 0)),
    ("LeftArm", "LeftShoulder", (14, 0, 0)), ("LeftForeArm", "LeftArm", (28, 0, 0)),
    ("LeftHand", "LeftForeArm", (25, 0, 0)), ("LeftHandIndex", "LeftHand", (8, 0, 0)),
    ("LeftHandPinky", "LeftHand", (7, 0, -2)), ("LeftHandThumb", "LeftHand", (3, 0, 3)),
    ("RightShoulder", "Chest", (-4, 10, 0)), ("RightArm", "RightShoulder", (-14, 0, 0)),
    ("RightForeArm", "RightArm", (-28, 0, 0)), ("RightHand", "RightForeArm", (-25, 0, 0)),
    ("RightHandIndex", "RightHand", (-8, 0, 0)), ("RightHandPinky", "RightHand", (-7, 0, -2)),
    ("RightHandThumb", "RightHand", (-3, 0, 3)), ("LeftUpLeg", "Hips", (9, -5, 0)),
    ("LeftLeg", "LeftUpLeg", (0, -42, 0)), ("LeftFoot", "LeftLeg", (0, -40, 0)),
    ("LeftToeBase", "LeftFoot", (0, -5, 12)), ("LeftToeEnd", "LeftToeBase", (0, 0, 5)),
    ("RightUpLeg", "Hips", (-9, -5, 0)), ("RightLeg", "RightUpLeg", (0, -42, 0)),
    ("RightFoot", "RightLeg", (0, -40, 0)), ("RightToeBase", "RightFoot", (0, -5, 12)),
    ("RightToeEnd", "RightToeBase", (0, 0, 5)),
]  # fmt: skip


@dataclass(frozen=True)
class Dataset:
    name: str
    paths: tuple[Path, ...]
    megabytes: float


@dataclass(frozen=True)
class Timing:
    """Median wall-clock and CPU (process) seconds of one engine on one dataset."""

    dataset: str
    engine: str
    what: str
    runs: int
    seconds: float
    cpu_seconds: float
    megabytes: float

    @property
    def mb_per_s(self) -> float:
        return self.megabytes / self.seconds


# ---------------------------------------------------------------- data


def body_skeleton() -> Skeleton:
    names = [name for name, _, _ in BODY_31]
    parents = [names.index(parent) if parent else -1 for _, parent, _ in BODY_31]
    leaves = [j for j in range(len(names)) if j not in parents]
    return Skeleton(
        names=tuple(names),
        parents=np.array(parents, dtype=np.int64),
        offsets=np.array([offset for _, _, offset in BODY_31], dtype=np.float64),
        channels=(("Xposition", "Yposition", "Zposition", *ROTATION),)
        + (ROTATION,) * (len(names) - 1),
        end_site_parents=np.array(leaves, dtype=np.int64),
        end_site_offsets=np.tile([0.0, 5.0, 0.0], (len(leaves), 1)),
    )


def smooth_motion(skeleton: Skeleton, seconds: float, fps: float, seed: int = 0) -> Motion:
    """Sums of three random sinusoids (0.05–1.5 Hz) per channel: ±30° joints, a walking root."""
    rng = np.random.default_rng(seed)
    t = np.arange(round(seconds * fps))[:, None] / fps
    n_channels = skeleton.n_channels
    freq = rng.uniform(0.05, 1.5, (3, n_channels))
    phase = rng.uniform(0, 2 * np.pi, (3, n_channels))
    amplitude = rng.uniform(2.0, 12.0, (3, n_channels))
    frames = sum(amplitude[k] * np.sin(2 * np.pi * freq[k] * t + phase[k]) for k in range(3))
    frames = np.asarray(frames, dtype=np.float64)
    frames[:, :3] += skeleton.offsets[0] + np.hstack([10 * t, 0 * t, 5 * t])  # slow drift
    frames[:, 5] += 90 * np.sin(2 * np.pi * t[:, 0] / seconds)  # heading turns over the take
    return Motion(skeleton, frames, 1.0 / fps)


def prepare(data: Path, workdir: Path, n_files: int | None) -> list[Dataset]:
    """Decompress the sessions and write the synthetic file (both outside the timing)."""
    sessions = sorted((data / "sessions").glob("*.bvh.gz"))[:n_files]
    if not sessions:
        raise SystemExit(f"no sessions under {data / 'sessions'}")
    plain = []
    for path in sessions:
        target = workdir / path.name.removesuffix(".gz")
        target.write_bytes(gzip.decompress(path.read_bytes()))
        plain.append(target)
    synthetic = workdir / "synthetic_60s_120fps_31j.bvh"
    write(smooth_motion(body_skeleton(), 60.0, 120.0), synthetic)
    size = sum(p.stat().st_size for p in plain) / 1e6
    return [
        Dataset(f"UI-PRMD sessions ({len(plain)} files)", tuple(plain), size),
        Dataset(
            "synthetic 60 s × 120 fps × 31 joints", (synthetic,), synthetic.stat().st_size / 1e6
        ),
    ]


# ---------------------------------------------------------------- engines


def ours_read(paths: Sequence[Path]) -> None:
    for path in paths:
        read(path)


def ours_read_positions(paths: Sequence[Path]) -> None:
    for path in paths:
        positions(read(path))


def bvh_parse(paths: Sequence[Path]) -> None:
    import bvh

    for path in paths:
        mocap = bvh.Bvh(path.read_text())
        np.array(mocap.frames, dtype=np.float64)


def bvhio_hierarchy(paths: Sequence[Path]) -> None:
    import bvhio

    for path in paths:
        bvhio.readAsHierarchy(str(path))


def median_seconds(run: Callable[[], object], runs: int) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def engines(
    args: argparse.Namespace,
) -> list[tuple[str, str, Callable[[Sequence[Path]], None], int]]:
    table: list[tuple[str, str, Callable[[Sequence[Path]], None], int]] = [
        ("this project", "read", ours_read, args.runs),
        ("this project", "read + positions", ours_read_positions, args.runs),
        (f"bvh {_version('bvh')}", "Bvh(text) + float array", bvh_parse, args.bvh_runs),
    ]
    if args.bvhio_runs > 0:  # 0: leave bvhio out (minutes per corpus run)
        table.append(
            (f"bvhio {_version('bvhio')}", "readAsHierarchy", bvhio_hierarchy, args.bvhio_runs)
        )
    return table


def measure(datasets: list[Dataset], args: argparse.Namespace) -> list[Timing]:
    """Runs are interleaved (one run of every engine per round), so that the load of the shared
    machine falls alike on all engines instead of on whichever ran during a busy minute."""
    table = engines(args)
    ours_read_positions(datasets[0].paths[:1])  # load the compiled kernels first
    out = []
    for data in datasets:
        for path in data.paths:
            path.read_bytes()  # same page-cache state for every engine
        ours_read_positions(data.paths)  # untimed: first-touch costs of the process's heap
        wall: list[list[float]] = [[] for _ in table]
        cpu: list[list[float]] = [[] for _ in table]
        for round_ in range(max(runs for *_, runs in table)):
            for k, (_, _, fn, runs) in enumerate(table):
                if round_ < runs:
                    start_cpu, start = time.process_time(), time.perf_counter()
                    fn(data.paths)
                    wall[k].append(time.perf_counter() - start)
                    cpu[k].append(time.process_time() - start_cpu)
        for k, (engine, what, _, runs) in enumerate(table):
            seconds, cpu_s = statistics.median(wall[k]), statistics.median(cpu[k])
            out.append(Timing(data.name, engine, what, runs, seconds, cpu_s, data.megabytes))
            print(f"  {data.name}: {engine} {what}: {seconds:.3f} s", file=sys.stderr)
    return out


def positions_ms(path: Path, runs: int = 21) -> tuple[float, tuple[int, ...]]:
    motion = read(path)
    shape = positions(motion).shape
    return 1e3 * median_seconds(lambda: positions(motion), runs), shape


# ---------------------------------------------------------------- report


def _version(package: str) -> str:
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        raise SystemExit(f"{package} is missing: .venv/bin/pip install bvh bvhio") from None


def machine() -> str:
    try:
        lscpu = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
        model = next(
            line.split(":", 1)[1].strip() for line in lscpu.splitlines() if "Model name" in line
        )
    except (OSError, subprocess.CalledProcessError, StopIteration):
        model = platform.processor() or "unknown CPU"
    return f"{model}, {os.cpu_count()} cores, Python {platform.python_version()}"


def table(timings: list[Timing]) -> list[str]:
    lines = [
        "| data | MB | engine | timed | runs | median s | MB/s | ours × faster | CPU s | CPU × |",
        "|---|---:|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for t in timings:
        ours = next(o for o in timings if o.dataset == t.dataset and o.what == "read + positions")
        mine = t.engine == "this project"
        ratio = "—" if mine else f"{t.seconds / ours.seconds:.1f}"
        cpu_ratio = "—" if mine else f"{t.cpu_seconds / ours.cpu_seconds:.1f}"
        lines.append(
            f"| {t.dataset} | {t.megabytes:.1f} | {t.engine} | {t.what} | {t.runs} | "
            f"{t.seconds:.3f} | {t.mb_per_s:.1f} | {ratio} | {t.cpu_seconds:.3f} | {cpu_ratio} |"
        )
    return lines


def verdicts(timings: list[Timing], pos_ms: float) -> list[str]:
    lines = []
    for data in dict.fromkeys(t.dataset for t in timings):
        row = {t.what: t for t in timings if t.dataset == data}
        ours = row["read + positions"]
        vs_bvh = row["Bvh(text) + float array"].seconds / ours.seconds
        cpu_vs_bvh = row["Bvh(text) + float array"].cpu_seconds / ours.cpu_seconds
        vs_bvhio = (
            f"{row['readAsHierarchy'].seconds / ours.seconds:.0f}× faster than bvhio (target ≥ "
            f"{TARGETS['vs_bvhio']:.0f}×: "
            f"{_ok(row['readAsHierarchy'].seconds / ours.seconds >= TARGETS['vs_bvhio'])})"
            if "readAsHierarchy" in row
            else "bvhio not run"
        )
        read_speed = row["read"].mb_per_s
        lines.append(
            f"- {data}: {vs_bvh:.1f}× faster than bvh (target ≥ {TARGETS['vs_bvh']:.0f}×: "
            f"{_ok(vs_bvh >= TARGETS['vs_bvh'])}; by processor time {cpu_vs_bvh:.1f}×, issue 37 "
            f"target ≥ {TARGETS['vs_bvh_cpu']:.0f}×: {_ok(cpu_vs_bvh >= TARGETS['vs_bvh_cpu'])}), "
            f"{vs_bvhio}, reading {read_speed:.0f} MB/s (target ≥ {TARGETS['read_mb_s']:.0f}: "
            f"{_ok(read_speed >= TARGETS['read_mb_s'])})"
        )
    lines.append(
        f"- positions for 60 s × 120 fps × 31 joints: {pos_ms:.1f} ms (target < "
        f"{TARGETS['positions_ms']:.0f} ms: {_ok(pos_ms < TARGETS['positions_ms'])})"
    )
    return lines


def _ok(passed: bool) -> str:
    return "met" if passed else "MISSED"


def report(
    timings: list[Timing], pos_ms: float, shape: tuple[int, ...], args: argparse.Namespace
) -> str:
    command = ".venv/bin/python -m bench.bench_bvh " + " ".join(sys.argv[1:])
    lines = [
        "## BVH reading and forward kinematics (bench/bench_bvh.py)",
        "",
        f"Measured {datetime.date.today().isoformat()} on {machine()} (shared 2-core VM).",
        f"Command: `{command.strip()}`",
        "",
        "Same uncompressed files for every engine (decompressed before timing); the corpus row",
        "is all files read one after the other. `bvh` only tokenises (no positions), `bvhio`",
        "builds per-frame joint transforms. Median of the runs shown (bvhio: fewer runs, it is",
        "slow); the engines' runs are interleaved round by round. *ours × faster*: this engine's",
        "wall-clock time over this project's read + positions; *CPU s* / *CPU ×*: the same with",
        "process CPU time, less sensitive to the other users of the machine. Verdicts use",
        "wall-clock time.",
        "",
        *table(timings),
        "",
        f"Positions alone for the synthetic file, {shape} output: {pos_ms:.2f} ms"
        " (median of 21 runs).",
        "",
        *verdicts(timings, pos_ms),
    ]
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=Path("data/ui-prmd"))
    parser.add_argument("--runs", type=int, default=5, help="runs for this project")
    parser.add_argument("--bvh-runs", type=int, default=5)
    parser.add_argument("--bvhio-runs", type=int, default=3, help="0 leaves bvhio out")
    parser.add_argument("--files", type=int, default=None, help="only the first N sessions")
    parser.add_argument("--markdown", type=Path, default=None, help="also write the report here")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bench_bvh_") as tmp:
        datasets = prepare(args.data, Path(tmp), args.files)
        timings = measure(datasets, args)
        pos_ms, shape = positions_ms(datasets[1].paths[0])
    text = report(timings, pos_ms, shape, args)
    print(text)
    if args.markdown:
        args.markdown.write_text(text)


if __name__ == "__main__":
    main()
