"""Kinect v2 files as recorders and data sets write them, not as this repository's writers do.

- SDK dumps without a header: one frame per line, the SDK's 25 joints in its order (`KINECT_V2`),
  each x y z (75 values), x y z and the tracking state (100: 0 not tracked, 1 inferred, 2
  tracked), or x y z and the orientation quaternion qx qy qz qw (175, as the KERAAL data set
  writes them); a leading time stamp is allowed (76, 101, 176); comma, semicolon, tab or space
  separated, trailing separators ignored; an empty line (or one of zeros) is a frame in which no
  body was tracked.
- Per-joint CSVs with a header and whatever other columns the recorder adds (subject, labels,
  projected coordinates): the joint-name, X, Y, Z, tracking-state and time columns are found by
  name, case-insensitively, in their common spellings; a new frame starts when a joint repeats.

Both give tracks by the SDK's joint names (metres, camera space) and `Tracking`: which positions
the sensor only inferred (`bridge_inferred` fills short runs of them from tracked frames).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.sources.errors import CaptureFileError
from analysis.sources.names import KINECT_V2
from analysis.sources.tables import FloatArray, check_frames, fps_from_times, number, text_of

BoolArray = npt.NDArray[np.bool_]
N_JOINTS = len(KINECT_V2)
PER_JOINT = {3: "x, y, z", 4: "x, y, z and tracking state", 7: "x, y, z and orientation"}
NOT_TRACKED, INFERRED = 0, 1
STATES = {"nottracked": 0, "inferred": 1, "tracked": 2}
# An inferred run this long or shorter (frames) is filled in from the tracked frames around it;
# a longer one is kept, since a straight line over half a second misses a whole movement.
BRIDGE_FRAMES = 15
_SPLIT = re.compile(r"[,;\t ]+")


@dataclass(frozen=True)
class Tracking:
    """Frames without a body (T,) and joints the sensor inferred ({joint: (T,) bool})."""

    empty: BoolArray
    inferred: dict[str, BoolArray]


def is_numeric_line(line: str) -> bool:
    cells = [c for c in _SPLIT.split(line.strip()) if c]
    return bool(cells) and all(_is_number(c) for c in cells[:8])


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def numeric_rows(content: bytes) -> list[list[float] | None]:
    """Each line's numbers (None for an empty line: no body); trailing separators dropped."""
    rows: list[list[float] | None] = []
    for n, line in enumerate(text_of(content).splitlines()):
        cells = [c for c in _SPLIT.split(line.strip()) if c]
        rows.append([number(c, f"Line {n + 1}") for c in cells] if cells else None)
    while rows and rows[-1] is None:
        rows.pop()
    return rows


def frame_width(rows: list[list[float] | None]) -> int:
    """The values per line of a dump (the commonest length of a non-empty line)."""
    lengths = [len(r) for r in rows if r is not None]
    if not lengths:
        raise CaptureFileError("The file holds no numbers.")
    values, counts = np.unique(lengths, return_counts=True)
    return int(values[np.argmax(counts)])


def read_dump(
    rows: list[list[float] | None],
) -> tuple[dict[str, FloatArray], float | None, Tracking, str]:
    """Tracks of a headerless dump, the rate if it has time stamps, tracking, and the layout."""
    width = frame_width(rows)
    timed = width - 1 in (N_JOINTS * k for k in PER_JOINT)
    per = (width - timed) // N_JOINTS
    if per not in PER_JOINT or (width - timed) % N_JOINTS:
        raise CaptureFileError(
            f"The lines hold {width} values; a Kinect dump holds 25 joints of 3, 4 or 7 values "
            "(75, 100 or 175 per line)."
        )
    check_frames(len(rows))
    values = np.full((len(rows), width), np.nan)
    for r, row in enumerate(rows):
        if row is not None and len(row) != width:
            raise CaptureFileError(f"Line {r + 1} holds {len(row)} values, not {width}.")
        if row is not None:
            values[r] = row
    times = values[:, 0] if timed else None
    joints = values[:, int(timed) :].reshape(len(rows), N_JOINTS, per)
    empty = np.all(np.isnan(joints[..., :3]) | (joints[..., :3] == 0), axis=(1, 2))
    xyz = joints[..., :3].copy()
    xyz[empty] = np.nan
    state = joints[..., 3] if per == 4 else np.full(xyz.shape[:2], 2.0)
    if per == 4 and not np.all(np.isin(state[~empty], (0, 1, 2))):
        raise CaptureFileError("The fourth value of each joint is not a tracking state (0, 1, 2).")
    fps = fps_from_times(times) if times is not None else None
    tracks, tracking = _tracks(xyz, state, empty)
    layout = f"Kinect SDK dump without a header, 25 joints × {PER_JOINT[per]} per line"
    return tracks, fps, tracking, layout


def _tracks(
    xyz: FloatArray, state: FloatArray, empty: BoolArray
) -> tuple[dict[str, FloatArray], Tracking]:
    xyz = xyz.copy()
    xyz[state == NOT_TRACKED] = np.nan
    tracks = {name: xyz[:, k] for k, name in enumerate(KINECT_V2)}
    inferred = {name: (state[:, k] == INFERRED) & ~empty for k, name in enumerate(KINECT_V2)}
    return tracks, Tracking(empty, inferred)


def _plain(header: str) -> str:
    return re.sub(r"[^0-9a-z]", "", header.lower())


JOINT_COLUMN = ("jointname", "jointtype", "joint", "jointid", "bodypart", "name")
STATE_COLUMN = ("trackingstatus", "trackingstate", "jointtrackingstate", "tracking", "state")
TIME_COLUMN = ("relativetime", "timestamp", "time", "timems", "times", "frame", "frameno")


def per_joint_columns(header: list[str]) -> dict[str, int] | None:
    """{"joint", "x", "y", "z"[, "state", "time"]: column} of a per-joint Kinect CSV, or None.
    X, Y, Z are the plain names (``X``, ``x``, ``PositionX``, ``Position.X``, ``X_pos``), never
    the projected ones (``X_proj``, ``ColorX``, ``DepthX``)."""
    plain = [_plain(h) for h in header]
    found: dict[str, int] = {}
    for role, names in (("joint", JOINT_COLUMN), ("state", STATE_COLUMN)):
        k = next((plain.index(n) for n in names if n in plain), None)
        if k is not None:
            found[role] = k
    for axis in "xyz":
        spellings = (axis, f"position{axis}", f"{axis}pos", f"{axis}position", f"camera{axis}")
        k = next((plain.index(n) for n in spellings if n in plain), None)
        if k is not None:
            found[axis] = k
    time = next((k for k, p in enumerate(plain) for n in TIME_COLUMN if p.startswith(n)), None)
    if time is not None:
        found["time"] = time
    return found if {"joint", "x", "y", "z"} <= set(found) else None


def read_per_joint(
    rows: list[list[str]],
) -> tuple[dict[str, FloatArray], float | None, Tracking]:
    """Tracks by the file's joint names from a per-joint CSV (header first)."""
    header, body = rows[0], rows[1:]
    cols = per_joint_columns(header)
    if cols is None:
        raise CaptureFileError("The header needs a joint-name column and X, Y, Z columns.")
    frames: list[dict[str, tuple[list[float], float]]] = [{}]
    stamps: list[float] = []
    for r, row in enumerate(body):
        if len(row) <= max(cols.values()):
            raise CaptureFileError(f"Row {r + 2} has fewer values than the header names.")
        joint = row[cols["joint"]]
        if joint in frames[-1]:
            frames.append({})
        if not frames[-1] and "time" in cols:
            stamps.append(number(row[cols["time"]], f"Row {r + 2}'s time"))
        xyz = [number(row[cols[a]], f"Row {r + 2}") for a in "xyz"]
        frames[-1][joint] = (xyz, _state(row[cols["state"]]) if "state" in cols else 2.0)
    check_frames(len(frames))
    names = list(dict.fromkeys(j for frame in frames for j in frame))
    points = np.full((len(frames), len(names), 3), np.nan)
    state = np.full((len(frames), len(names)), 2.0)
    for f, frame in enumerate(frames):
        for k, name in enumerate(names):
            if name in frame:
                points[f, k], state[f, k] = frame[name]
    empty = np.all(np.isnan(points), axis=(1, 2))
    points[state == NOT_TRACKED] = np.nan
    inferred = {n: (state[:, k] == INFERRED) for k, n in enumerate(names)}
    tracks = {n: points[:, k] for k, n in enumerate(names)}
    fps = fps_from_times(np.array(stamps)) if stamps else None
    return tracks, fps, Tracking(empty, inferred)


def _state(cell: str) -> float:
    plain = _plain(cell)
    if plain in STATES:
        return float(STATES[plain])
    value = number(cell, "A tracking state")
    return 2.0 if np.isnan(value) else value


def bridge_inferred(
    tracks: dict[str, FloatArray], tracking: Tracking
) -> tuple[dict[str, FloatArray], int, int]:
    """Inferred positions in runs of at most `BRIDGE_FRAMES` set missing (the solver fills them
    from the tracked frames around them); longer runs kept. Returns the tracks, the positions
    filled in and the positions kept as inferred."""
    out, filled, kept = {}, 0, 0
    for name, given in tracks.items():
        flags = tracking.inferred.get(name)
        track = given.copy()
        if flags is not None and flags.any():
            for start, stop in _runs(flags):
                if stop - start <= BRIDGE_FRAMES:
                    track[start:stop] = np.nan
                    filled += stop - start
                else:
                    kept += stop - start
        out[name] = track
    return out, filled, kept


def _runs(flags: BoolArray) -> list[tuple[int, int]]:
    edges = np.diff(np.concatenate(([0], flags.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True))
