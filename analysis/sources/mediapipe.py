"""MediaPipe / BlazePose world landmarks (33 points, metres, origin between the hips, y down).

Files: JSON, a list of frames (or ``{"fps": …, "frames": [...]}``), each frame a list of 33
``{x, y, z, visibility}`` (or ``{"landmarks": [...]}``; empty or null where no person was found);
CSV as MediaPipe examples write: frame, landmark (index or name), x, y, z, visibility.

`motion_from_landmarks` is the one way landmarks become a motion, for files and video alike.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from analysis.sources.errors import CaptureFileError
from analysis.sources.ik import Solved, solve
from analysis.sources.names import MEDIAPIPE, canonical
from analysis.sources.tables import DEFAULT_FPS, FloatArray, check_frames, y_down_to_up

N_LANDMARKS = len(MEDIAPIPE)
MIN_VISIBILITY = 0.5  # MediaPipe's own threshold for drawing a landmark


def landmark_points(world: FloatArray) -> dict[str, FloatArray]:
    """Canonical points (y up) of (T, 33, 3) landmarks; the head is the midpoint of the ears."""
    tracks = {name: world[:, k] for k, name in enumerate(MEDIAPIPE)}
    points = {canonical(n): t for n, t in tracks.items() if canonical(n) is not None}
    points["head"] = (tracks["left_ear"] + tracks["right_ear"]) / 2
    return y_down_to_up({str(k): v for k, v in points.items()})


def motion_from_landmarks(
    world: FloatArray, fps: float, found: np.ndarray | None = None, smoothing: int = 3
) -> Solved:
    """The motion of (T, 33, 3) world landmarks in metres at ``fps``; frames where ``found`` (T,)
    is False (no person) are bridged like any missing point. ``smoothing``: frames the rotations
    are averaged over (3 by default: a video estimator's landmarks jitter from frame to frame;
    landmark files pass 1, as their recorders filter already)."""
    world = np.asarray(world, dtype=np.float64)
    if world.ndim != 3 or world.shape[1:] != (N_LANDMARKS, 3):
        raise CaptureFileError(f"Landmarks must be {N_LANDMARKS} points (x, y, z) per frame.")
    check_frames(world.shape[0])
    if found is not None:
        world = world.copy()
        world[~np.asarray(found, dtype=bool)] = np.nan
    if np.nanmax(np.abs(world), initial=0.0) > 100.0:
        raise CaptureFileError("The landmarks are far too large to be metres around a person.")
    return solve(landmark_points(world), fps, smoothing)


def landmarks_from_json(data: Any) -> tuple[FloatArray, float]:
    """(T, 33, 3) landmarks (NaN where not visible) and the frame rate of a landmark JSON."""
    fps = DEFAULT_FPS
    frames = data
    if isinstance(data, dict):
        frames, fps = data.get("frames"), data.get("fps", DEFAULT_FPS)
        if isinstance(fps, bool) or not isinstance(fps, int | float):
            raise CaptureFileError("The JSON's fps is not a number.")
    if not isinstance(frames, list):
        raise CaptureFileError("The JSON is not a list of landmark frames.")
    check_frames(len(frames))
    out = np.full((len(frames), N_LANDMARKS, 3), np.nan)
    for f, entry in enumerate(frames):
        marks = entry
        if isinstance(entry, dict):
            marks = entry.get("landmarks") or entry.get("world_landmarks")
        if not marks:
            continue
        out[f] = _frame(marks, f)
    return out, float(fps)


def _frame(frame: Any, f: int) -> FloatArray:
    if not isinstance(frame, list) or len(frame) != N_LANDMARKS:
        raise CaptureFileError(f"Frame {f + 1} does not hold {N_LANDMARKS} landmarks.")
    out = np.full((N_LANDMARKS, 3), np.nan)
    for k, mark in enumerate(frame):
        if not isinstance(mark, dict):
            raise CaptureFileError(f"Landmark {k} of frame {f + 1} is not an object.")
        try:
            xyz = [float(mark[a]) for a in ("x", "y", "z")]
            seen = float(mark.get("visibility", 1.0))
        except (KeyError, TypeError, ValueError):
            raise CaptureFileError(
                f"Landmark {k} of frame {f + 1} lacks numeric x, y, z."
            ) from None
        if seen >= MIN_VISIBILITY:
            out[k] = xyz
    return out


def landmarks_from_tracks(
    tracks: dict[str, FloatArray], visibility: dict[str, FloatArray]
) -> FloatArray:
    """(T, 33, 3) landmarks from a long CSV's tracks by name (NaN where hidden or absent)."""
    n = next(iter(tracks.values())).shape[0]
    out = np.full((n, N_LANDMARKS, 3), np.nan)
    for k, name in enumerate(MEDIAPIPE):
        if name in tracks:
            seen = visibility.get(name, np.ones(n)) >= MIN_VISIBILITY
            out[seen, k] = tracks[name][seen]
    return out
