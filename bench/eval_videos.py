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
import json
import os
import platform
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from analysis.bvh import Motion, read
from analysis.pipeline import FittedModel, analyse, build_model
from analysis.pipeline.model_fit import moving_joints
from analysis.sources import read_recording
from analysis.sources.mediapipe import motion_from_landmarks
from tests.analysis.fixtures.capture.make_video_landmarks import landmarks_file

ROOT = Path(__file__).resolve().parents[1]
CAPTURE = ROOT / "tests" / "analysis" / "fixtures" / "capture"
UI_PRMD = ROOT / "data" / "ui-prmd"
HIPS = (23, 24)  # MediaPipe's hip landmarks: world landmarks are centred between them
# (frames a second the browser's pose engine keeps up with, shift of its first frame in frames)
CAMERA_RATES = ((10.5, 0.0), (12.0, 0.5), (15.0, 0.0), (15.0, 0.5), (20.0, 0.0), (20.0, 0.5))
# The browser test's clip (every third frame, 1.5 times slower) and the page's steady rate
# (`webapp/live/camera_views.py`); pose engine results a second on a software renderer.
CLIP_STEP, CLIP_SLOWER, PAGE_FPS = 3, 1.5, 15.0
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


def ui_prmd_model(code: str) -> FittedModel:
    """The exercise as the demo clinic builds it: subject s01's correct session, its key poses
    from `landmarks.csv`, the body parts that move between them."""
    relative = f"sessions/{code}_s01_correct.bvh.gz"
    with open(UI_PRMD / "landmarks.csv", newline="") as handle:
        row = next(r for r in csv.DictReader(handle) if r["file"] == relative)
    frames = [int(v) for v in row["frames"].split(";")]
    types = [int(v) for v in row["types"].split(";")]
    tutor = read(UI_PRMD / relative)
    return build_model(tutor, frames, types, joints=moving_joints(tutor, frames, types))


def stored_landmarks(video: str) -> tuple[np.ndarray, np.ndarray, float]:
    """The world landmarks (T, 33, 3), found (T,) and frame rate stored beside ``video``
    (`tests/analysis/fixtures/capture/make_video_landmarks.py`)."""
    stored = np.load(landmarks_file(video))
    return stored["world"].astype(np.float64), stored["found"], float(stored["fps"])


def upload_motion(video: str) -> Motion:
    """The recording the site makes of the video, from its stored landmarks."""
    world, found, fps = stored_landmarks(video)
    return motion_from_landmarks(world, fps, found).motion


def camera_recording(world: np.ndarray, fps: float, rate: float, shift: float) -> Motion:
    """What a camera session of a video saves: the landmarks of the frames the browser's pose
    engine took (``rate`` a second, starting ``shift`` of a frame late), centred on the hips as
    MediaPipe's world landmarks are, as a landmark file read back like any upload."""
    world = world - world[:, HIPS].mean(axis=1, keepdims=True)
    taken = np.round((np.arange(int(world.shape[0] / fps * rate)) + shift) * fps / rate)
    return landmark_file(world[taken[taken < world.shape[0]].astype(np.int64)], rate)


def page_recording(world: np.ndarray, fps: float, engine_rate: float, seed: int) -> Motion:
    """A camera session of the video as the browser test plays it (`tests/live/camera_clips.py`:
    every `CLIP_STEP`-th frame, `CLIP_SLOWER` times slower): the pose engine finds a body about
    ``engine_rate`` times a second, at irregular moments (``seed``), and the page sends
    `PAGE_FPS` frames a second interpolated between its results (`camera_page.js`)."""
    rng = np.random.default_rng(seed)
    shown = np.arange(0, world.shape[0], CLIP_STEP)  # the clip's frames, at these wall times:
    at = shown / fps * CLIP_SLOWER
    times = [0.0]
    while times[-1] < at[-1]:
        times.append(times[-1] + rng.uniform(0.6, 1.4) / engine_rate)
    found = np.array(times[:-1])
    poses = world[shown[np.searchsorted(at, found, side="right") - 1]]
    poses = poses - poses[:, HIPS].mean(axis=1, keepdims=True)
    ticks = np.arange(0.0, found[-1], 1.0 / PAGE_FPS)
    k = np.clip(np.searchsorted(found, ticks, side="right") - 1, 0, found.size - 2)
    share = np.clip((ticks - found[k]) / (found[k + 1] - found[k]), 0.0, 1.0)[:, None, None]
    sent = poses[k] + share * (poses[k + 1] - poses[k])
    return landmark_file(sent, PAGE_FPS)


def landmark_file(world: np.ndarray, rate: float) -> Motion:
    """(T, 33, 3) world landmarks saved as a camera session saves them, read back."""
    frames = [
        [{"x": x, "y": y, "z": z, "visibility": 1.0} for x, y, z in pose.tolist()] for pose in world
    ]
    content = json.dumps({"fps": rate, "source": "camera", "frames": frames}).encode()
    return read_recording("camera.json", content).motion


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
    motion = motion_from_landmarks(seen.world, seen.header.fps, seen.found).motion
    return motion, seen.world, seen.header.fps


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
