"""MediaPipe Pose over a video file, one contiguous slice of the video per core.

MediaPipe releases the GIL while it works on a frame, so one thread per slice keeps every core
busy without a process pool (a Celery pool process may not start processes of its own). Each
thread has its own decoder and its own tracker: tracking needs the frames in order, so a slice
is a run of consecutive frames, not every n-th one. A slice after the first starts ``WARM_UP``
frames early and drops those results: by its first kept frame its tracker has found the body
and its landmark smoothing has settled (landmarks within a few millimetres of one pass over the
whole video; tracking carries its history, so not bit for bit). The
frames before the warm-up are only grabbed (decoded, not converted nor tracked); seeking by
frame number would be faster but lands on the wrong frame in variable-frame-rate phone videos.
So are the frames between the read ones when only every n-th is read (a 60 fps video at 30).

Where a frame's processor time goes (lite model, docs/PERFORMANCE.md, "Phone video"): about
two thirds in MediaPipe's network, a tenth in decoding, the rest in MediaPipe's crop of the
body, colour conversion and Python. Handing MediaPipe a smaller picture saves nothing (it crops
and scales the body itself) and moves the landmarks; the decoder's thread count changes nothing
measurable.

Models: the full landmark model ships in the wheel; the lite one is the project's copy in
``data/models/`` (see its README), put beside MediaPipe's own when first asked for, since
MediaPipe would otherwise download it from the network, which this project never does. Which one
reads uploads: `analysis.sources.video.DEFAULT_MODEL`, and why: docs/PERFORMANCE.md, "Phone video".
"""

from __future__ import annotations

import concurrent.futures as cf
import os
import shutil
import tempfile
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.sources.errors import CaptureFileError
from analysis.sources.names import MEDIAPIPE

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
Progress = Callable[[float], None]

LANDMARKS = len(MEDIAPIPE)
PROGRESS_EVERY = 15  # frames per progress report: each report is a database write in the worker
MAX_FRAMES = 108_000  # an hour at 30 frames per second
WARM_UP = 30  # frames a later slice tracks before its first kept frame (1 s at 30 fps)
MIN_SLICE = 150  # frames: a shorter slice does not pay for a second tracker's start and warm-up
MAX_SLICES = 8
LITE_MODEL = Path(__file__).resolve().parents[2] / "data" / "models" / "pose_landmark_lite.tflite"
COMPLEXITY = {"lite": 0, "full": 1}
_LOCK = threading.Lock()


def libraries() -> tuple[ModuleType, ModuleType]:
    """OpenCV and MediaPipe's pose solution, loaded when a video is read: they take about 1 s
    and a hundred megabytes to load, which every web and worker process would otherwise pay for
    BVH files too. (Third-party libraries, not project modules: no import cycle is involved.)"""
    # MediaPipe's native code logs each model it loads to stderr: noise in a worker's log
    # (warnings and errors still show). Set before the native libraries load, which read it once.
    os.environ.setdefault("GLOG_minloglevel", "2")
    import cv2
    from mediapipe.python.solutions import pose

    return cv2, pose


def pose_model(wanted: str = "lite") -> str:
    """The landmark model to use: ``wanted`` ("lite" or "full"), but "full" when the lite one's
    weights are neither where MediaPipe looks for them nor can be put there (MediaPipe would
    otherwise try to download them)."""
    if wanted not in COMPLEXITY:
        raise ValueError(f"unknown pose model {wanted!r}: 'lite' or 'full'")
    if wanted == "full":
        return "full"
    _, pose = libraries()
    target = Path(str(pose.__file__)).resolve().parents[2] / "modules" / "pose_landmark"
    target = target / LITE_MODEL.name
    with _LOCK:
        if target.is_file():
            return "lite"
        if not LITE_MODEL.is_file():
            return "full"
        try:  # copied whole, then renamed: a reader never sees half a model
            with tempfile.NamedTemporaryFile(dir=target.parent, delete=False) as handle:
                shutil.copyfileobj(LITE_MODEL.open("rb"), handle)
            os.replace(handle.name, target)
        except OSError:
            return "full"
    return "lite"


def slices(frames: int, workers: int | None = None, step: int = 1) -> list[tuple[int, int | None]]:
    """Contiguous (start, stop) frame ranges, one per worker, each starting on a frame that is
    read (a multiple of ``step``); the last reads to the end (the container's frame count can be
    short)."""
    cores = workers or len(os.sched_getaffinity(0))
    count = max(1, min(cores, MAX_SLICES, frames // MIN_SLICE))
    cuts = [step * round(k * frames / count / step) for k in range(count + 1)]
    return [(cuts[k], cuts[k + 1] if k + 1 < count else None) for k in range(count)]


def track_slices(
    path: str,
    frames: int,
    model: str,
    progress: Progress | None,
    *,
    workers: int | None = None,
    step: int = 1,
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """(T, 33, 3) world and picture landmarks (NaN where nobody was found) and found (T,) of
    every ``step``-th frame of the video; ``model`` as `pose_model` resolves it."""
    model = pose_model(model)
    ranges = slices(frames, workers, step)
    done = [0] * len(ranges)
    read = -(-frames // step)  # frames given to MediaPipe, for the progress reports
    if len(ranges) == 1:
        whole = Slice(0, None, step, model)
        parts = [_track(path, whole, done, 0, progress=progress, expected=read)]
    else:
        with cf.ThreadPoolExecutor(len(ranges), thread_name_prefix="pose") as pool:
            futures = [
                pool.submit(_track, path, Slice(start, stop, step, model), done, k)
                for k, (start, stop) in enumerate(ranges)
            ]
            _report_while_running(futures, done, read, progress)
            parts = [f.result() for f in futures]
    world, picture, found = (np.concatenate(arrays) for arrays in zip(*parts, strict=True))
    if found.size < 2:
        raise CaptureFileError("This video holds fewer than two frames that could be decoded.")
    return world, picture, found


def _report_while_running(
    futures: list[cf.Future[Any]], done: list[int], frames: int, progress: Progress | None
) -> None:
    """Progress from the calling thread only (each report may be a database write, and a
    database connection belongs to the thread that opened it)."""
    last = 0
    while cf.wait(futures, timeout=0.5).not_done:
        now = sum(done)
        if progress is not None and frames > 0 and now - last >= PROGRESS_EVERY:
            progress(min(1.0, now / frames))
            last = now


@dataclass(frozen=True)
class Slice:
    """Frames ``start`` to ``stop`` (None: the end) of a video, every ``step``-th one through
    MediaPipe's ``model``."""

    start: int
    stop: int | None
    step: int
    model: str


def _track(
    path: str,
    part: Slice,
    done: list[int],
    slot: int,
    *,
    progress: Progress | None = None,
    expected: int = 0,
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """One slice's landmarks; ``done[slot]`` counts its frames read so far; ``progress`` (of the
    ``expected`` frames) is called from this thread: only when it is the caller's."""
    cv2, mediapipe_pose = libraries()
    first = max(0, part.start - WARM_UP * part.step)
    capture = cv2.VideoCapture(path)
    try:
        for _ in range(first):
            if not capture.grab():
                return _empty()
        end = MAX_FRAMES if part.stop is None else min(part.stop, MAX_FRAMES)
        with mediapipe_pose.Pose(
            static_image_mode=False, model_complexity=COMPLEXITY[part.model]
        ) as tracker:
            reader = _Reader(capture, tracker, cv2, part.step)
            rows = reader.frames(end - first, done, slot, progress, expected)
    finally:
        capture.release()
    world, picture, found = rows
    keep = (part.start - first) // part.step
    return world[keep:], picture[keep:], found[keep:]


@dataclass
class _Reader:
    """A slice's decoder and tracker: every ``step``-th frame to MediaPipe, the others decoded
    only (decoding must go through every frame; colour conversion and tracking need not)."""

    capture: Any
    tracker: Any
    cv2: ModuleType
    step: int

    def frames(
        self, count: int, done: list[int], slot: int, progress: Progress | None, expected: int
    ) -> tuple[FloatArray, FloatArray, BoolArray]:
        """Landmarks of the next ``count`` frames' read ones; ``done[slot]`` counts them."""
        world: list[FloatArray] = []
        picture: list[FloatArray] = []
        found: list[bool] = []
        nowhere = np.full((LANDMARKS, 3), np.nan)
        for index in range(count):
            if index % self.step:
                if not self.capture.grab():
                    break
                continue
            ok, frame = self.capture.read()
            if not ok:
                break
            result = self.tracker.process(self.cv2.cvtColor(frame, self.cv2.COLOR_BGR2RGB))
            seen = result.pose_world_landmarks is not None and result.pose_landmarks is not None
            world.append(_points(result.pose_world_landmarks) if seen else nowhere)
            picture.append(_points(result.pose_landmarks) if seen else nowhere)
            found.append(seen)
            done[slot] = len(found)
            if progress is not None and expected > 0 and len(found) % PROGRESS_EVERY == 0:
                progress(min(1.0, len(found) / expected))
        if not found:
            return _empty()
        return np.stack(world), np.stack(picture), np.array(found, dtype=bool)


def _empty() -> tuple[FloatArray, FloatArray, BoolArray]:
    return np.empty((0, LANDMARKS, 3)), np.empty((0, LANDMARKS, 3)), np.empty(0, dtype=bool)


def _points(landmarks: object) -> FloatArray:
    """MediaPipe's landmark list (a protobuf message) as a (33, 3) array."""
    return np.array([(p.x, p.y, p.z) for p in landmarks.landmark], dtype=np.float64)  # type: ignore[attr-defined]
