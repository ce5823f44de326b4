"""Kinect v2 / Azure Kinect joint positions: CSV (wide: a row per frame, a column per joint
coordinate such as ``SpineBase_X`` or ``SpineBase.x``; long: a row per joint per frame with a time
or frame column, a joint-name column and X, Y, Z) and Azure Kinect Body Tracking JSON
(``frames[].bodies[].joint_positions``, millimetres, the SDK's 32 joints in its order)."""

from __future__ import annotations

import json
import re
from typing import Any

import numpy as np

from analysis.sources.errors import CaptureFileError
from analysis.sources.names import AZURE, canonical
from analysis.sources.tables import (
    DEFAULT_FPS,
    FloatArray,
    check_frames,
    fps_from_times,
    number,
    y_down_to_up,
)

_COORD = re.compile(r"^(.*?)[\s_.:-]*\(?([xyz])\)?$", re.IGNORECASE)
TIME_NAMES = ("time", "timestamp", "relativetime", "seconds", "t")
FRAME_NAMES = ("frame", "frameno", "framenumber", "frame#", "index")
JOINT_NAMES = ("joint", "jointname", "jointtype", "name", "landmark", "bodypart", "marker")


def _plain(header: str) -> str:
    return re.sub(r"[^0-9a-z#]", "", header.lower())


def wide_columns(header: list[str]) -> dict[str, dict[str, int]]:
    """{joint name: {"x"/"y"/"z": column}} for columns named ``<joint><sep><axis>``."""
    joints: dict[str, dict[str, int]] = {}
    for k, name in enumerate(header):
        m = _COORD.match(name)
        if m and m.group(1):
            joints.setdefault(m.group(1), {})[m.group(2).lower()] = k
    return {j: axes for j, axes in joints.items() if len(axes) == 3}


def column(header: list[str], names: tuple[str, ...]) -> int | None:
    plain = [_plain(h) for h in header]
    for name in names:
        if name in plain:
            return plain.index(name)
    return None


def read_wide(rows: list[list[str]]) -> tuple[dict[str, FloatArray], float | None, list[str]]:
    """Raw tracks by the file's joint names, the frame rate if time stamps give it, and the
    joint names found."""
    header, body = rows[0], rows[1:]
    joints = wide_columns(header)
    if not joints:
        raise CaptureFileError("No joint position columns (such as SpineBase_X) in the header.")
    check_frames(len(body))
    width = len(header)
    values = np.full((len(body), width), np.nan)
    for r, row in enumerate(body):
        if len(row) < width:
            raise CaptureFileError(f"Row {r + 2} has {len(row)} values; the header names {width}.")
        for k in sorted({c for axes in joints.values() for c in axes.values()}):
            values[r, k] = number(row[k], f"Row {r + 2}, column {header[k]},")
    time = column(header, TIME_NAMES)
    fps = fps_from_times(values_of(body, time)) if time is not None else None
    tracks = {j: values[:, [a["x"], a["y"], a["z"]]] for j, a in joints.items()}
    return tracks, fps, list(joints)


def values_of(body: list[list[str]], k: int) -> FloatArray:
    return np.array([number(row[k], "The time column") if k < len(row) else np.nan
                     for row in body])  # fmt: skip


def long_columns(header: list[str]) -> tuple[int, int, tuple[int, int, int]] | None:
    """(time-or-frame column, joint column, x/y/z columns) of a long layout, or None."""
    when = column(header, TIME_NAMES + FRAME_NAMES)
    joint = column(header, JOINT_NAMES)
    axes = [column(header, (a,)) for a in ("x", "y", "z")]
    if when is None or joint is None or None in axes:
        return None
    return when, joint, (axes[0], axes[1], axes[2])  # type: ignore[return-value]


def read_long(
    rows: list[list[str]], names: tuple[str, ...] = ()
) -> tuple[dict[str, FloatArray], float | None, list[str], dict[str, FloatArray]]:
    """Tracks by joint name from a long layout; ``names`` turns index joint columns (MediaPipe's
    0–32) into names. Also returns extra per-joint columns (``visibility``) when present."""
    header, body = rows[0], rows[1:]
    found = long_columns(header)
    if found is None:
        raise CaptureFileError(
            "The header needs a time or frame column, a joint column and X, Y, Z columns."
        )
    when, joint, axes = found
    extra = column(header, ("visibility", "confidence", "trackingstate"))
    stamps: dict[float, int] = {}
    cells: list[tuple[int, str, list[float], float]] = []
    for r, row in enumerate(body):
        if len(row) <= max(when, joint, *axes):
            raise CaptureFileError(f"Row {r + 2} has fewer values than the header names.")
        stamp = number(row[when], f"Row {r + 2}'s time")
        if not np.isfinite(stamp):
            raise CaptureFileError(f"Row {r + 2} has no time or frame number.")
        frame = stamps.setdefault(stamp, len(stamps))
        xyz = [number(row[a], f"Row {r + 2}") for a in axes]
        seen = number(row[extra], f"Row {r + 2}") if extra is not None and extra < len(row) else 1
        cells.append((frame, joint_name(row[joint], names), xyz, seen))
    check_frames(len(stamps))
    tracks: dict[str, FloatArray] = {}
    visibility: dict[str, FloatArray] = {}
    for frame, name, xyz, seen in cells:
        tracks.setdefault(name, np.full((len(stamps), 3), np.nan))[frame] = xyz
        visibility.setdefault(name, np.ones(len(stamps)))[frame] = seen
    fps = fps_from_times(np.array(list(stamps))) if _plain(header[when]) in TIME_NAMES else None
    return tracks, fps, list(tracks), visibility


def joint_name(cell: str, names: tuple[str, ...]) -> str:
    if names and cell.isdigit():
        k = int(cell)
        if k >= len(names):
            raise CaptureFileError(f"Joint number {k} is not one of the {len(names)} known.")
        return names[k]
    return cell


def to_canonical(
    tracks: dict[str, FloatArray],
) -> tuple[dict[str, FloatArray], list[str], list[str]]:
    """Tracks under canonical point names, with the file's names used and not used."""
    points: dict[str, FloatArray] = {}
    used, unused = [], []
    for name, track in tracks.items():
        point = canonical(name)
        if point is None or point in points:
            unused.append(name)
        else:
            points[point] = track
            used.append(name)
    return points, used, unused


def read_azure(data: Any) -> tuple[dict[str, FloatArray], float, list[str]]:
    """Azure Kinect Body Tracking JSON: the first body of each frame (NaN where none), in metres
    with y up."""
    frames = data.get("frames") if isinstance(data, dict) else None
    if not isinstance(frames, list):
        raise CaptureFileError("The JSON has no list of frames.")
    names = data.get("joint_names") or AZURE
    if not isinstance(names, list | tuple) or not all(isinstance(n, str) for n in names):
        raise CaptureFileError("The JSON's joint names are not a list of names.")
    check_frames(len(frames))
    values = np.full((len(frames), len(names), 3), np.nan)
    stamps = np.full(len(frames), np.nan)
    for f, frame in enumerate(frames):
        if not isinstance(frame, dict):
            raise CaptureFileError(f"Frame {f + 1} of the JSON is not an object.")
        stamps[f] = _float(frame.get("timestamp_usec", np.nan), f)
        bodies = frame.get("bodies") or []
        if bodies:
            values[f] = _positions(bodies[0], len(names), f)
    if np.all(np.isnan(values)):
        raise CaptureFileError("No frame of the JSON holds a body.")
    fps = fps_from_times(stamps * 1e-6) or DEFAULT_FPS
    tracks = {n: values[:, k] / 1000.0 for k, n in enumerate(names)}
    return y_down_to_up(tracks), fps, list(names)


def _float(value: Any, f: int) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or abs(value) > 1e300:
        raise CaptureFileError(f"Frame {f + 1} of the JSON has a time that is not a number.")
    return float(value)


def _positions(body: Any, n: int, f: int) -> FloatArray:
    joints = body.get("joint_positions") if isinstance(body, dict) else None
    try:
        out = np.array(joints, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        out = None
    if out is None or out.shape != (n, 3):
        raise CaptureFileError(f"Frame {f + 1}'s body does not hold {n} joint positions (x, y, z).")
    return out


def load_json(content: bytes) -> Any:
    try:
        return json.loads(content)
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as error:
        kind = error.__class__.__name__
        raise CaptureFileError(f"The file is not valid JSON ({kind}).") from None
