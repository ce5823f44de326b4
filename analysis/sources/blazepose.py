"""BlazePose / MediaPipe Pose landmarks keyed by frame and landmark name, as data sets store them:
``{"positions": {frame: {landmark name: [x, y, z]}}}`` (the KERAAL data set; names such as
``Left_shoulder`` in any case), optionally with ``fps``, ``width``/``height`` and ``mirrored``.

- Frames are the keys' numbers: a frame without a person is left out of such files without a
  gap, so the keys (not the order) give each frame's time, and the missing ones are bridged.
- Coordinates are world metres (origin between the hips) or image-normalised (x, y in [0, 1] of
  the picture's width and height, y down; z the depth relative to the hips on x's scale). Image
  coordinates are scaled by the picture's proportions (from the file, else estimated from the body:
  hip-to-ankle height about 1.45 times the widest shoulder span, as a Kinect's joints measured
  1.35 to 1.67 on the KERAAL takes; the nearest common proportion is taken) to a body of 1.7 m;
  their depth is MediaPipe's estimate, relative, and says little.
- KERAAL's BlazePose ran on mirrored frames: its "left" landmarks are the person's right. Files of
  that layout (``positions`` and capitalised names) are mirrored back unless they say
  ``"mirrored": false``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.sources.errors import CaptureFileError
from analysis.sources.names import MEDIAPIPE, key
from analysis.sources.tables import DEFAULT_FPS, FloatArray, check_frames

_INDEX = {key(name): k for k, name in enumerate(MEDIAPIPE)}
BODY_HEIGHT_M = 1.7
# Common pictures' width / height; an estimate from the body snaps to the nearest.
ASPECTS = {"16:9": 16 / 9, "4:3": 4 / 3, "1:1": 1.0, "3:4": 3 / 4, "9:16": 9 / 16}
LEG_PER_SHOULDER_WIDTH = 1.45  # hip-to-ankle height over the widest shoulder span (joints)
MAX_FRAME_NUMBER = 10_000_000
UPPER_BODY = slice(0, 23)  # head, shoulders and arms: landmarks 0–22


@dataclass(frozen=True)
class KeyedLandmarks:
    """(T, 33, 3) landmarks in metres, MediaPipe's world axes (y down), NaN where not found;
    the frame rate; notes for the import report."""

    world: FloatArray
    fps: float
    notes: tuple[str, ...]


def is_keyed(data: Any) -> bool:
    positions = data.get("positions") if isinstance(data, dict) else None
    return isinstance(positions, dict) and bool(positions)


def read_keyed(data: dict[str, Any]) -> KeyedLandmarks:
    positions = data["positions"]
    numbers = [_frame_number(k) for k in positions]
    first, last = min(numbers), max(numbers)
    if last - first > MAX_FRAME_NUMBER:
        raise CaptureFileError("The JSON's frame numbers are too far apart to be one take.")
    check_frames(last - first + 1)
    world = np.full((last - first + 1, len(MEDIAPIPE), 3), np.nan)
    for number, frame in zip(numbers, positions.values(), strict=True):
        world[number - first] = _frame(frame, number)
    fps = _fps(data.get("fps", DEFAULT_FPS))
    notes = []
    if "fps" not in data:
        notes.append(f"The file gives no frame rate; {DEFAULT_FPS:g} frames per second assumed.")
    missing = (last - first + 1) - len(numbers)
    if missing:
        notes.append(f"No person was found in {missing} frames; they were filled in.")
    world, more = _to_metres(world, data)
    notes += more
    if data.get("mirrored", _keraal_style(positions)) is not False:
        world = mirrored(world)
        notes.append(
            "The landmarks were found on a mirrored picture; left and right were swapped back."
        )
    return KeyedLandmarks(world, fps, tuple(notes))


def _frame_number(text: str) -> int:
    try:
        value = float(text)
    except ValueError:
        raise CaptureFileError(f"The JSON's frame key {text[:20]!r} is not a number.") from None
    if not np.isfinite(value) or value < 0 or value != int(value):
        raise CaptureFileError(f"The JSON's frame key {text[:20]!r} is not a frame number.")
    return int(value)


def _fps(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise CaptureFileError("The JSON's fps is not a number.")
    return float(value)


def _frame(frame: Any, number: int) -> FloatArray:
    if not isinstance(frame, dict):
        raise CaptureFileError(f"Frame {number} of the JSON is not an object of landmarks.")
    out = np.full((len(MEDIAPIPE), 3), np.nan)
    for name, xyz in frame.items():
        k = _INDEX.get(key(name))
        if k is None:
            continue
        try:
            out[k] = np.asarray(xyz, dtype=np.float64)[:3]
        except (TypeError, ValueError, IndexError):
            raise CaptureFileError(f"Landmark {name} of frame {number} is not x, y, z.") from None
    return out


def _keraal_style(positions: dict[str, Any]) -> bool:
    """KERAAL's writer: capitalised landmark names (``Left_shoulder``)."""
    frame = next(iter(positions.values()))
    return isinstance(frame, dict) and "Left_shoulder" in frame


def is_image_normalised(world: FloatArray) -> bool:
    """World landmarks have their origin between the hips; image ones put the hips inside the
    picture (x, y between 0 and 1)."""
    middle = (world[:, 23, :2] + world[:, 24, :2]) / 2
    middle = middle[np.all(np.isfinite(middle), axis=1)]
    if middle.size == 0:
        raise CaptureFileError("The landmarks have no hips in any frame.")
    hips = np.median(middle, axis=0)
    return bool(np.all(np.abs(hips) > 0.05) and np.all((hips > 0) & (hips < 1)))


def _to_metres(world: FloatArray, data: dict[str, Any]) -> tuple[FloatArray, list[str]]:
    if not is_image_normalised(world):
        return world, ["The landmarks were read as world positions in metres."]
    width, height = data.get("width"), data.get("height")
    if isinstance(width, int | float) and isinstance(height, int | float) and _positive(width) \
            and _positive(height):  # fmt: skip
        aspect, how = float(width) / float(height), f"{width}×{height} (from the file)"
    else:
        name = estimated_aspect(world)
        aspect, how = ASPECTS[name], f"{name} (estimated from the body; the file does not say)"
    scaled = upright_in_depth(world * np.array([aspect, 1.0, aspect]))
    scale = BODY_HEIGHT_M / _body_height(scaled)
    note = (
        "The landmarks are in picture coordinates: scaled with the picture's proportions "
        f"{how} to a body {BODY_HEIGHT_M:g} m tall; their depth is estimated from the picture, "
        "relative, so movements towards or away from the camera read roughly, and leaning "
        "towards or away from the camera is not measured."
    )
    return scaled * scale, [note]


def upright_in_depth(world: FloatArray) -> FloatArray:
    """The upper body moved in depth so the shoulders' middle is as deep as the hips' middle,
    keeping each landmark's depth relative to it: a single camera's relative depth puts a seated
    person's shoulders tens of centimetres before the hips (a 35–60° forward lean while the
    Kinect of the same KERAAL take reads 4–16°), and that lean, the trunk's frame, turned a
    sideways bend of 30° into one of 15°. The shoulders' turn (one before the other) stays."""
    shoulders = (world[:, 11, 2] + world[:, 12, 2]) / 2
    hips = (world[:, 23, 2] + world[:, 24, 2]) / 2
    out = world.copy()
    out[:, UPPER_BODY, 2] -= (shoulders - hips)[:, None]
    return out


def _positive(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and value > 0


def estimated_aspect(world: FloatArray) -> str:
    """The common picture proportion under which a standing body has adult proportions."""
    dy = np.abs(world[:, 27, 1] - world[:, 23, 1]) + np.abs(world[:, 28, 1] - world[:, 24, 1])
    shoulders = np.abs(world[:, 11, 0] - world[:, 12, 0])
    ok = np.isfinite(dy) & np.isfinite(shoulders) & (shoulders > 1e-3)
    if not ok.any():
        return "4:3"
    # Legs upright across the picture's height; shoulders across its width at their widest
    # (a turned trunk shows them narrower).
    ratio = float(np.median(dy[ok]) / 2 / np.percentile(shoulders[ok], 90))
    wanted = ratio / LEG_PER_SHOULDER_WIDTH  # = width / height
    return min(ASPECTS, key=lambda n: abs(np.log(ASPECTS[n] / wanted)))


def _body_height(world: FloatArray) -> float:
    """Nose to the lower ankle, median over frames, plus a tenth for the top of the head."""
    ankles = np.fmax(world[:, 27, 1], world[:, 28, 1])
    height = np.abs(ankles - world[:, 0, 1]) * 1.1
    height = height[np.isfinite(height) & (height > 0)]
    if height.size == 0:
        raise CaptureFileError("The landmarks have no nose and ankles to size the body from.")
    return float(np.median(height))


def mirrored(world: FloatArray) -> FloatArray:
    """Landmarks of a mirrored picture turned back: x negated, left and right swapped."""
    order = [MEDIAPIPE.index(_other_side(name)) for name in MEDIAPIPE]
    out = world[:, order].copy()
    out[..., 0] *= -1
    return out


def _other_side(name: str) -> str:
    if "left" in name:
        return name.replace("left", "right")
    return name.replace("right", "left")
