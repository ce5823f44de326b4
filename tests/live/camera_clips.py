"""Clips for Chromium's fake camera (``--use-file-for-fake-video-capture``): YUV4MPEG2 (`.y4m`),
raw 4:2:0 frames the browser plays in a loop at the header's rate, written with OpenCV (already
in the environment for the video uploads) from the repository's own test video.

- `squat_clip`: the phone video of two squats (tests/analysis/fixtures/capture, licence beside
  it), every third frame, smaller, and played ``slower`` times slower than filmed: the pose
  engine on a software renderer finds a few frames a second, and a slower clip gives it more
  of each squat. ``between`` keeps only that part of the video (seconds as filmed): the
  squats bottom near 10.2 s and 16.8 s, the lifter stands still from the start to 9 s and racks
  the bar from 19 s.
- `empty_room_clip`: a still picture of an empty room (a wall, a floor, a door): no person.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import cv2
import numpy as np

VIDEO = Path(__file__).resolve().parents[1] / "analysis/fixtures/capture/side_squat_2reps.mp4"


def _header(width: int, height: int, fps: Fraction) -> bytes:
    rate = f"F{fps.numerator}:{fps.denominator}"
    return f"YUV4MPEG2 W{width} H{height} {rate} Ip A1:1 C420jpeg\n".encode()


def _frame(picture: np.ndarray) -> bytes:
    return b"FRAME\n" + cv2.cvtColor(picture, cv2.COLOR_BGR2YUV_I420).tobytes()


def squat_clip(
    path: Path,
    *,
    slower: float = 1.5,
    step: int = 3,
    width: int = 240,
    between: tuple[float, float] = (0.0, float("inf")),
) -> tuple[Path, float]:
    """The squat video as a `.y4m` clip; returns the path and the clip's length in seconds."""
    capture = cv2.VideoCapture(str(VIDEO))
    filmed_fps = capture.get(cv2.CAP_PROP_FPS)
    fps = Fraction(filmed_fps / step / slower).limit_denominator(100)
    first, last = round(between[0] * filmed_fps), between[1] * filmed_fps  # frame indices
    frames = 0
    with path.open("wb") as out:
        index = 0
        while index <= last:
            ok, picture = capture.read()
            if not ok:
                break
            if index >= first and (index - first) % step == 0:
                h, w = picture.shape[:2]
                size = (width, int(h * width / w) // 2 * 2)
                small = cv2.resize(picture, size, interpolation=cv2.INTER_AREA)
                if frames == 0:
                    out.write(_header(*size, fps))
                out.write(_frame(small))
                frames += 1
            index += 1
    capture.release()
    return path, frames / float(fps)


def empty_room_clip(path: Path, *, seconds: int = 4, fps: int = 5) -> Path:
    """A still `.y4m` picture of an empty room, ``seconds`` long."""
    height, width = 480, 360
    room = np.zeros((height, width, 3), np.uint8)
    room[:] = (200, 215, 225)  # a pale wall
    room[int(height * 0.7) :] = (90, 110, 140)  # the floor
    cv2.rectangle(room, (220, 150), (310, int(height * 0.7)), (60, 80, 110), -1)  # a door
    cv2.rectangle(room, (40, 90), (150, 180), (230, 230, 235), -1)  # a window
    with path.open("wb") as out:
        out.write(_header(width, height, Fraction(fps)))
        for _ in range(seconds * fps):
            out.write(_frame(room))
    return path
