"""Shared reading helpers: text and CSV rows with limits, frame rates from time stamps, units."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from analysis.sources.errors import CaptureFileError

FloatArray = npt.NDArray[np.float64]
MAX_FRAMES = 500_000
MAX_COORDINATE_M = 100.0  # a body part 100 m from the camera is a broken file, not a person
DEFAULT_FPS = 30.0


def text_of(content: bytes) -> str:
    try:
        return content.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise CaptureFileError("The file is not text (it is not UTF-8 encoded).") from None


def csv_rows(content: bytes) -> list[list[str]]:
    """The rows of a CSV (comma, semicolon or tab separated), empty rows dropped."""
    text = text_of(content)
    sample = text[:4096]
    delimiter = max((",", ";", "\t"), key=sample.count)
    rows = [[c.strip() for c in row] for row in csv.reader(io.StringIO(text), delimiter=delimiter)]
    rows = [r for r in rows if any(r)]
    if len(rows) < 2:
        raise CaptureFileError("The file has no data rows under its header.")
    return rows


def number(text: str, what: str) -> float:
    """A float from a cell; an empty cell or 'nan' is a missing value (NaN)."""
    if text == "" or text.lower() in ("nan", "na", "null", "none"):
        return math.nan
    try:
        value = float(text)
    except ValueError:
        raise CaptureFileError(f"{what} holds {text[:20]!r}, which is not a number.") from None
    return value


def fps_from_times(times: FloatArray) -> float | None:
    """Frames per second from time stamps in seconds, milliseconds, microseconds or 100 ns ticks
    (Kinect's RelativeTime); None when they do not increase."""
    steps = np.diff(times[np.isfinite(times)])
    steps = steps[steps > 0]
    if steps.size == 0:
        return None
    step = float(np.median(steps))
    # Seconds, ms, µs, ticks: the first unit giving a recorder's usual rate, else the first
    # plausible one (Kinect ticks of 333 333 are 30 fps, not 3 fps in microseconds).
    for low, high in ((10.0, 250.0), (1.0, 1000.0)):
        for unit in (1.0, 1e-3, 1e-6, 1e-7):
            fps = 1.0 / (step * unit)
            if low <= fps <= high:
                return fps
    return None


def to_metres(points: dict[str, FloatArray], unit: str | None) -> tuple[dict[str, FloatArray], str]:
    """Points in metres. ``unit`` from the file ("mm", "cm", "m") or None: then guessed from the
    head-to-ankle distance (over 20 → mm, over 3 → cm)."""
    factor = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}.get((unit or "").lower())
    if factor is None:
        size = body_size(points)
        factor = 1e-3 if size > 20 else 1e-2 if size > 3 else 1.0
    scaled = {k: v * factor for k, v in points.items()}
    for track in scaled.values():
        if np.nanmax(np.abs(track), initial=0.0) > MAX_COORDINATE_M:
            raise CaptureFileError("The file's positions are far too large to be a person.")
    return scaled, {1e-3: "mm", 1e-2: "cm", 1.0: "m"}[factor]


def body_size(points: Mapping[str, FloatArray]) -> float:
    """Median distance from the head (or shoulders) to the ankles (or hips), file units."""
    top = points.get("head", points.get("left_shoulder"))
    low = points.get("left_ankle", points.get("left_hip"))
    if top is None or low is None:
        return 1.0
    d = np.linalg.norm(top - low, axis=1)
    d = d[np.isfinite(d)]
    return float(np.median(d)) if d.size else 1.0


def y_down_to_up(points: dict[str, FloatArray]) -> dict[str, FloatArray]:
    """Camera axes with y down (Azure Kinect, MediaPipe) turned half a turn about x: y up, still
    right-handed (a mirror would swap the body's sides)."""
    flip = np.array([1.0, -1.0, -1.0])
    return {k: v * flip for k, v in points.items()}


def z_up_to_y_up(points: dict[str, FloatArray]) -> dict[str, FloatArray]:
    """Points of a lab whose z axis is up (Vicon: x forward, y left, z up) in the solver's axes
    (y up): the axes turned (x, y, z) → (y, z, x), a rotation, so the body's sides stay. Left as
    they are unless the body stands along z (head above the ankles, median over the take)."""
    top, low = points.get("head"), points.get("left_ankle")
    if top is None or low is None:
        return points
    up = np.nanmedian(top - low, axis=0)
    if not np.all(np.isfinite(up)) or np.argmax(np.abs(up)) != 2 or up[2] <= 0:
        return points
    return {name: track[:, [1, 2, 0]] for name, track in points.items()}


def check_frames(n: int) -> None:
    if n < 2:
        raise CaptureFileError("The file holds fewer than two frames.")
    if n > MAX_FRAMES:
        raise CaptureFileError(f"The file holds {n} frames; at most {MAX_FRAMES} are accepted.")
