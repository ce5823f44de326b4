"""Time of a phone video's analysis against the video's own duration, and lite vs full model.

Timing: the video (default the squat fixture, 20.5 s) is looped into a temporary file of
``--seconds`` (60 s: 1,798 frames at 29.97 fps; written outside the timing), then each run reads
it as the worker reads an uploaded video (`analysis.sources.video.read_video`: MediaPipe Pose on
every frame read, one slice of the video per core, then the skeleton solved) and analyses it against
a squat exercise (`analysis.pipeline.analyse`, the model built from the fixture's reference
outside the timing).
The figure is wall time / video duration (target ≤ 0.5: a 60 s video in ≤ 30 s), with the
processor time (all threads) of reading and of analysing: divided by the duration and the cores,
the wall time the run would take on cores nobody else uses. Several ``--model`` and
``--read-fps`` (frames a second given to MediaPipe, `analysis.sources.video.READ_FPS` by
default) are timed in turn, run after run, so that they share the machine's load alike.

Comparison (``--compare``): each given video read with the lite and with the full landmark model
: frames with a person, repetitions and their bottoms (against the squat exercise), the knees'
and hips' clinical angle ranges, how far the lite landmarks are from the full ones, and how far
the sliced reading is from reading the video in one slice (as before slicing). With ``--truth``
(a ``.trc`` of the same movement from several cameras, frame for frame), each model's knee and
hip angles are also compared with the ones that recording gives: mean absolute difference.

    .venv/bin/python -m bench.bench_video [--video PATH] [--seconds 60] [--runs 3]
                                          [--model full|lite ...] [--read-fps 30 ...]
    .venv/bin/python -m bench.bench_video --compare VIDEO [VIDEO ...] [--truth TRC]
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import statistics
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from analysis.bvh import Motion, read
from analysis.bvh.errors import AnalysisInputError
from analysis.clinical import angle_series, clinical_angles
from analysis.pipeline import FittedModel, analyse, build_model
from analysis.sources import read_recording
from analysis.sources.mediapipe import motion_from_landmarks
from analysis.sources.pose_tracking import libraries
from analysis.sources.video import (
    DEFAULT_MODEL,
    READ_FPS,
    landmarks_from_video,
    probe,
    read_video,
)
from tests.analysis.fixtures.capture.make_squat_reference import (
    KEY_POSE_FRAMES,
    KEY_POSE_TYPES,
    REFERENCE,
    VIDEO,
)

ANGLES = ("knee_flexion_left", "knee_flexion_right", "hip_flexion_left", "hip_flexion_right")


def looped(source: Path, seconds: float, target: Path) -> Path:
    """``source`` played again and again until ``seconds``, written to ``target`` (mp4)."""
    cv2, _ = libraries()
    header = probe(source)
    wanted = round(seconds * header.fps)
    writer = cv2.VideoWriter(
        str(target), cv2.VideoWriter_fourcc(*"mp4v"), header.fps, (header.width, header.height)
    )
    written = 0
    while written < wanted:
        capture = cv2.VideoCapture(str(source))
        while written < wanted:
            ok, frame = capture.read()
            if not ok:
                break
            writer.write(frame)
            written += 1
        capture.release()
    writer.release()
    return target


@dataclass(frozen=True)
class Run:
    """One reading and analysis of the video: wall and processor seconds (all threads) of each
    step, repetitions found."""

    read_wall: float
    read_cpu: float
    analyse_wall: float
    analyse_cpu: float
    repetitions: int

    @property
    def wall(self) -> float:
        return self.read_wall + self.analyse_wall

    @property
    def cpu(self) -> float:
        return self.read_cpu + self.analyse_cpu


def one_run(path: Path, model: FittedModel, pose_model: str, read_fps: float) -> Run:
    cpu, start = time.process_time(), time.perf_counter()
    recording = read_video(path, model=pose_model, read_fps=read_fps)
    read_cpu, read_wall = time.process_time() - cpu, time.perf_counter() - start
    cpu, start = time.process_time(), time.perf_counter()
    result = analyse(recording.motion, model).summary
    analyse_cpu, analyse_wall = time.process_time() - cpu, time.perf_counter() - start
    return Run(read_wall, read_cpu, analyse_wall, analyse_cpu, len(result.repetitions))


def timing(args: argparse.Namespace) -> None:
    squat = build_model(read(REFERENCE), list(KEY_POSE_FRAMES), list(KEY_POSE_TYPES))
    cores = len(os.sched_getaffinity(0))
    configs = [(m, f) for m in args.model for f in args.read_fps]
    with tempfile.TemporaryDirectory() as tmp:
        path = looped(args.video, args.seconds, Path(tmp) / "looped.mp4")
        header = probe(path)
        duration = header.frames / header.fps
        print(
            f"## Phone video ({dt.datetime.now(dt.UTC):%Y-%m-%d %H:%M} UTC, {cores} cores, "
            f"load average {os.getloadavg()[0]:.2f} at the start)\n\n"
            f"{args.video.name} looped to {duration:.1f} s ({header.frames} frames, "
            f"{header.width}×{header.height}, {header.fps:.2f} fps), {args.runs} runs of each "
            "model and reading rate, interleaved\n"
        )
        runs: dict[tuple[str, float], list[Run]] = {c: [] for c in configs}
        for k in range(args.runs):
            for config in configs:
                run = one_run(path, squat, *config)
                runs[config].append(run)
                print(
                    f"run {k + 1}, {config[0]} model, read at {config[1]:g} fps: read "
                    f"{run.read_wall:.1f} s wall / {run.read_cpu:.1f} s CPU, analyse "
                    f"{run.analyse_wall:.2f} s wall / {run.analyse_cpu:.2f} s CPU, "
                    f"{run.repetitions} repetitions (load {os.getloadavg()[0]:.1f})",
                    flush=True,
                )
    print()
    for (pose_model, read_fps), done in runs.items():
        wall = statistics.median(r.wall for r in done)
        cpu = statistics.median(r.cpu for r in done)
        verdict = "met" if wall / duration <= 0.5 else "MISSED"
        print(
            f"- {pose_model}, read at {read_fps:g} fps: median {wall:.1f} s wall = "
            f"{wall / duration:.2f} of the duration (target ≤ 0.5: {verdict}); CPU {cpu:.1f} s "
            f"({statistics.median(r.analyse_cpu for r in done):.2f} s of it analysing) = "
            f"{cpu / duration / cores:.2f} of the duration if every core were free"
        )
    print(f"\nload average at the end {os.getloadavg()[0]:.2f}")


def compare(videos: list[Path], truth: Path | None) -> None:
    squat = build_model(read(REFERENCE), list(KEY_POSE_FRAMES), list(KEY_POSE_TYPES))
    for video in videos:
        print(f"## {video.name}\n")
        seen = {}
        for label, model, workers in (("full", "full", None), ("lite", "lite", None)):
            start = time.perf_counter()
            seen[label] = landmarks_from_video(video, model=model, workers=workers)
            took = time.perf_counter() - start
            lm = seen[label]
            motion = motion_from_landmarks(lm.world, lm.fps, lm.found).motion
            _describe(label, motion, lm.found, took, squat)
            if truth is not None and lm.header.frames == _frames_of(truth):
                _against_truth(label, motion, truth)
        _landmark_gap("lite vs full world landmarks", seen["full"].world, seen["lite"].world)
        one = landmarks_from_video(video, model="lite", workers=1).world
        _landmark_gap("lite, sliced vs one slice", one, seen["lite"].world)


def _describe(label: str, motion: Motion, found: np.ndarray, took: float, squat: object) -> None:
    angles = clinical_angles(motion)
    try:
        summary = analyse(motion, squat).summary  # type: ignore[arg-type]
    except AnalysisInputError as error:  # e.g. a take too short to hold a squat
        squats = f"not analysed as squats ({error})"
    else:
        bottoms = ", ".join(f"{r.peak / motion.fps:.1f} s" for r in summary.repetitions)
        squats = f"squat repetitions {len(summary.repetitions)} (bottoms {bottoms or 'none'})"
    print(
        f"- {label}: person in {int(found.sum())}/{found.size} frames, landmarks in {took:.1f} s; "
        + squats
    )
    for name in ANGLES:
        if name in angles:
            a = angles[name]
            print(f"    {name}: {a.min:.1f}° … {a.max:.1f}° (range {a.range:.1f}°)")


def _frames_of(trc: Path) -> int:
    return read_recording(trc.name, trc.read_bytes()).motion.n_frames


def _against_truth(label: str, motion: Motion, trc: Path) -> None:
    """Mean absolute difference of each knee and hip angle from the multi-camera recording's."""
    reference = angle_series(read_recording(trc.name, trc.read_bytes()).motion)
    ours = angle_series(motion)
    parts = []
    for name in ANGLES:
        if name in ours and name in reference:
            gap = np.abs(ours[name] - reference[name])
            parts.append(f"{name} {np.nanmean(gap):.1f}°")
    print(f"    {label} vs the multi-camera .trc, mean absolute difference: " + ", ".join(parts))


def _landmark_gap(label: str, a: np.ndarray, b: np.ndarray) -> None:
    gap = np.linalg.norm(a - b, axis=-1) * 1000.0  # metres to mm
    gap = gap[np.isfinite(gap)]
    print(
        f"- {label}: median {np.median(gap):.0f} mm, "
        f"95th percentile {np.percentile(gap, 95):.0f} mm\n"
    )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--video", type=Path, default=VIDEO)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--model", choices=("lite", "full"), nargs="+", default=[DEFAULT_MODEL])
    parser.add_argument(
        "--read-fps", type=float, nargs="+", default=[READ_FPS], help="frames a second read"
    )
    parser.add_argument("--compare", type=Path, nargs="+", help="compare lite and full on these")
    parser.add_argument("--truth", type=Path, help="a .trc of the compared video's movement")
    args = parser.parse_args(argv)
    if args.compare:
        compare(args.compare, args.truth)
    else:
        timing(args)


if __name__ == "__main__":
    main()
