"""The recordings the video counting checks start from: the capture samples' stored landmarks
read as an upload, camera sessions of them as the browser's pose engine would take the frames,
and the UI-PRMD exercises made as the demo clinic makes them. Shared by
`tests/analysis/test_video_counts.py` and `bench/eval_videos.py`, which prints the same counts.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from analysis.bvh import Motion, read
from analysis.pipeline import FittedModel, build_model
from analysis.pipeline.model_fit import moving_joints
from analysis.sources import read_recording
from analysis.sources.mediapipe import motion_from_landmarks
from tests.analysis.fixtures.capture.make_video_landmarks import landmarks_file

ROOT = Path(__file__).resolve().parents[1]
CAPTURE = ROOT / "tests" / "analysis" / "fixtures" / "capture"
UI_PRMD = ROOT / "data" / "ui-prmd"
HIPS = (23, 24)  # MediaPipe's hip landmarks: world landmarks are centred between them
# The browser test's clip (every third frame, 1.5 times slower) and the page's steady rate
# (`webapp/live/camera_views.py`).
CLIP_STEP, CLIP_SLOWER, PAGE_FPS = 3, 1.5, 15.0


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
