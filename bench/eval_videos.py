"""Phone videos against references made from UI-PRMD BVH files of the same exercise (issue 35
item 5, issue 36): for each capture sample of `tests/analysis/fixtures/capture/` (copies of the
shared data's `capture/`, licences beside them), the repetitions counted against each UI-PRMD
exercise that matches it, the exercise made as the demo clinic makes it (subject s01's correct
Kinect session, its key poses from `data/ui-prmd/landmarks.csv`).

Each video is counted as an upload (every frame through MediaPipe Pose, as the site reads it), as
camera sessions (the frames a browser's pose engine takes, at several steady rates, saved as a
landmark file and read back) and as the camera page records the browser test's clip (a few pose
results a second, interpolated to the page's 15 frames a second): the count the page's offline
analysis reports (`tests/e2e/test_camera_page.py`).

    python -m bench.eval_videos            # reads the videos (about a minute on one free core)
    python -m bench.eval_videos --stored   # the landmarks stored beside them instead
    python -m bench.eval_videos --ui-prmd  # and UI-PRMD's counts (Kinect sessions, Vicon takes)
"""

from __future__ import annotations

import argparse
import csv
import gzip
import os
import platform
import time
from dataclasses import dataclass

import numpy as np

from analysis.bvh import Motion, read
from analysis.pipeline import FittedModel, analyse
from analysis.sources import read_recording
from analysis.sources.mediapipe import motion_from_landmarks
from tests.video_cases import (
    CAPTURE,
    UI_PRMD,
    camera_recording,
    page_recording,
    stored_landmarks,
    ui_prmd_model,
    upload_motion,
)

# (frames a second the browser's pose engine keeps up with, shift of its first frame in frames)
CAMERA_RATES = ((10.5, 0.0), (12.0, 0.5), (15.0, 0.0), (15.0, 0.5), (20.0, 0.0), (20.0, 0.5))
# Pose engine results a second on a software renderer, on the browser test's clip.
ENGINE_RATES = ((2.5, 0), (3.0, 0), (3.0, 1), (4.0, 0), (6.0, 0), (6.0, 1))
UI_PRMD_NAMES = {"m01": "deep squat", "m02": "hurdle step", "m06": "standing straight-leg raise"}


@dataclass(frozen=True)
class Sample:
    """A capture sample, the repetitions it shows, and the UI-PRMD exercises that match it."""

    file: str
    repetitions: int
    exercises: tuple[str, ...]
    note: str
    browser_clip: bool = False  # the browser test plays it on the camera page


# UI-PRMD has no balancing exercise: its hurdle step and straight-leg raise are the ones done
# standing on one leg while the other moves away and back. The KERAAL samples (trunk rotation,
# flank stretch, hiding the face) match no UI-PRMD exercise.
SAMPLES = (
    Sample("side_squat_2reps.mp4", 2, ("m01",), "barbell back squat, side view", True),
    Sample("pose2sim_balancing_cam01.mp4", 1, ("m02", "m06"), "single-leg balance, one camera"),
    Sample("pose2sim_balancing.trc", 1, ("m02", "m06"), "the same, triangulated from 4 views"),
)


def counted(motion: Motion, model: FittedModel) -> str:
    """The repetitions counted, or why none are (the recording does not fit the exercise)."""
    summary = analyse(motion, model).summary
    return str(len(summary.repetitions)) if summary.match.fits else "does not fit"


def video_world(sample: Sample, stored: bool) -> tuple[Motion, np.ndarray, float]:
    """The upload's recording and its world landmarks, from the video or the stored ones."""
    if stored:
        world, _, fps = stored_landmarks(sample.file)
        return upload_motion(sample.file), world, fps
    from analysis.sources.video import landmarks_from_video

    seen = landmarks_from_video(CAPTURE / sample.file)
    motion = motion_from_landmarks(seen.world, seen.fps, seen.found).motion
    return motion, seen.world, seen.fps


def rows(stored: bool) -> list[str]:
    models = {code: ui_prmd_model(code) for s in SAMPLES for code in s.exercises}
    out = []
    for sample in SAMPLES:
        camera: list[Motion] = []
        page: list[Motion] = []
        if sample.file.endswith(".mp4"):
            motion, world, fps = video_world(sample, stored)
            camera = [camera_recording(world, fps, rate, shift) for rate, shift in CAMERA_RATES]
            if sample.browser_clip:
                page = [page_recording(world, fps, rate, seed) for rate, seed in ENGINE_RATES]
        else:
            path = CAPTURE / sample.file
            motion = read_recording(path.name, path.read_bytes()).motion
        for code in sample.exercises:
            sessions = ", ".join(counted(m, models[code]) for m in camera) or "–"
            pages = ", ".join(counted(m, models[code]) for m in page) or "–"
            out.append(
                f"| `{sample.file}` ({sample.note}) | {sample.repetitions} | {code} "
                f"{UI_PRMD_NAMES[code]} | {counted(motion, models[code])} | {sessions} "
                f"| {pages} |"
            )
    return out


def ui_prmd_counts() -> str:
    """Exact repetition counts of UI-PRMD's development sessions (Kinect, s02-s07) and Vicon takes
    against the s01 Kinect exercises: the BVH sessions' counts, which the video rules must keep."""
    kinect = vicon = kinect_n = vicon_n = 0
    with open(UI_PRMD / "vicon" / "labels.csv", newline="") as handle:
        vicon_rows = list(csv.DictReader(handle))
    with open(UI_PRMD / "labels.csv", newline="") as handle:
        truths = {r["file"]: int(r["rep_count"]) for r in csv.DictReader(handle)}
    for code in sorted({f"m{k:02d}" for k in range(1, 11)}):
        model = ui_prmd_model(code)
        for subject in range(2, 8):
            for label in ("correct", "incorrect"):
                relative = f"sessions/{code}_s{subject:02d}_{label}.bvh.gz"
                found = analyse(read(UI_PRMD / relative), model).summary.repetitions
                kinect += len(found) == truths[relative]
                kinect_n += 1
        for row in (r for r in vicon_rows if r["exercise"] == code):
            path = UI_PRMD / "vicon" / row["file"]
            motion = read_recording(path.name[:-3], gzip.decompress(path.read_bytes())).motion
            truth = len(row["rep_start_frames"].split(";"))
            vicon += len(analyse(motion, model).summary.repetitions) == truth
            vicon_n += 1
    return (
        f"UI-PRMD exact counts: Kinect sessions {kinect}/{kinect_n}, Vicon takes {vicon}/{vicon_n}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--stored", action="store_true", help="stored landmarks, not the videos")
    parser.add_argument("--ui-prmd", action="store_true", help="UI-PRMD's counts as well")
    args = parser.parse_args()
    start = time.perf_counter()
    rates = ", ".join(f"{r:g}/s{' +½' if s else ''}" for r, s in CAMERA_RATES)
    engines = ", ".join(f"{r:g}/s" for r, _ in ENGINE_RATES)
    print("| sample | repetitions in it | UI-PRMD reference | counted as an upload "
          f"| camera sessions taking frames at {rates} "
          f"| the camera page on the browser test's clip, pose engine at {engines} |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    for row in rows(args.stored):
        print(row)
    if args.ui_prmd:
        print("\n" + ui_prmd_counts())
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    print(f"\n{platform.processor() or platform.machine()}, load {load}, "
          f"{time.perf_counter() - start:.0f} s")  # fmt: skip


if __name__ == "__main__":
    main()
