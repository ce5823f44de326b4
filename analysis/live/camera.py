"""Live sessions from a browser camera: MediaPipe Pose world landmarks, frame by frame, turned into
the rotations of the exercise's skeleton, which a live session aligns: the inverse kinematics of
`analysis.sources.ik` (the one that reads a MediaPipe landmark file) to a skeleton fitted to the
person, then `analysis.kinematics.map_onto` onto the exercise's, as the offline analysis does.

The browser sends each frame as 33 landmarks × (x, y, z, visibility), world coordinates in metres
(MediaPipe's: origin between the hips, y down), in the binary form of `analysis.live.frames` with
`VALUES_PER_FRAME` values per frame. `CameraStream`:

- fits the skeleton (bone lengths, the trunk's offsets) to the first frames in which every point
  the skeleton needs is visible: the BVH header the session then starts with;
- turns each later frame into that skeleton's channel values; a point hidden in a frame keeps its
  last seen position (a hand behind the back for a moment), as a file's gaps are bridged;
- keeps the landmarks, which become the session's recording: a MediaPipe landmark file
  (`recording_json`), read back by `analysis.sources.read_recording` like any other, so the
  offline analysis sees the frames the live one saw.

Each frame's rotations depend on that frame only (the offline reading of a landmark file does not
smooth either), so a frame costs no look-ahead and the live and the offline rotations agree.
"""

from __future__ import annotations

import json
from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion, Skeleton
from analysis.kinematics import map_onto
from analysis.kinematics import quaternions as quat
from analysis.live.session import header_text
from analysis.sources.errors import CaptureFileError
from analysis.sources.ik import (
    EULER_ORDER,
    JOINTS,
    REQUIRED,
    UNITS_PER_METRE,
    complete,
    global_rotations,
    local_quaternions,
    rest_offsets,
    standing_skeleton,
)
from analysis.sources.mediapipe import MIN_VISIBILITY, N_LANDMARKS, landmark_points
from analysis.sources.names import MEDIAPIPE

FloatArray = npt.NDArray[np.float64]
VALUES_PER_LANDMARK = 4  # x, y, z in metres, visibility 0 to 1
VALUES_PER_FRAME = N_LANDMARKS * VALUES_PER_LANDMARK
REST_DIRS = np.array([j[4] for j in JOINTS])
MAX_WORLD_M = 5.0  # MediaPipe's world landmarks lie within a body's reach of the hips


class CameraFrameError(ValueError):
    """Frames that cannot be landmarks of a person (the wrong count of values, metres beyond a
    body): the session answers with an error event saying so."""


def landmarks_of(values: FloatArray) -> FloatArray:
    """(n, 33, 3) world landmarks of (n, `VALUES_PER_FRAME`) values; NaN where a landmark's
    visibility is under MediaPipe's own threshold for drawing it."""
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 2 or values.shape[1] != VALUES_PER_FRAME:
        raise CameraFrameError(f"a camera frame holds {VALUES_PER_FRAME} values (33 landmarks × 4)")
    marks = values.reshape(-1, N_LANDMARKS, VALUES_PER_LANDMARK)
    world = marks[:, :, :3].copy()
    if np.nanmax(np.abs(world), initial=0.0) > MAX_WORLD_M:
        raise CameraFrameError("the landmarks lie further than a body reaches (metres expected)")
    world[marks[:, :, 3] < MIN_VISIBILITY] = np.nan
    return world


class CameraStream:
    """One camera session's conversion: landmarks in, the skeleton's channel values out."""

    def __init__(self, fps: float, target: Skeleton) -> None:
        if not np.isfinite(fps) or not 1.0 <= fps <= 120.0:
            raise CameraFrameError("the camera's frame rate must be 1 to 120 frames a second")
        self.fps, self.target = float(fps), target
        self.skeleton: Skeleton | None = None  # the person's, fitted to the first frames
        self.landmarks: list[FloatArray] = []  # (33, 3) per frame taken, NaN where not seen
        self._last: dict[str, FloatArray] = {}  # each point's last seen position (metres, y up)

    def header(self, values: FloatArray) -> str | None:
        """The BVH header of the skeleton fitted to the first frames of ``values`` in which every
        needed point is seen; None (and nothing fitted) while no such frame has come."""
        world = landmarks_of(values)
        points = landmark_points(world)
        whole = np.all([np.isfinite(points[n]).all(axis=1) for n in REQUIRED], axis=0)
        if not whole.any():
            return None
        seen = {name: track[whole] * UNITS_PER_METRE for name, track in points.items()}
        seen = {name: track for name, track in seen.items() if np.isfinite(track).all()}
        complete(seen)
        rotations = global_rotations(seen, REST_DIRS)
        offsets = rest_offsets(seen, rotations)
        self.skeleton = standing_skeleton(seen, offsets)
        empty = np.zeros((0, self.target.n_channels))
        return header_text(Motion(self.target, empty, 1.0 / self.fps))

    def channels(self, values: FloatArray) -> FloatArray:
        """The exercise skeleton's channel values (n, C) of ``values`` (n, `VALUES_PER_FRAME`)
        frames: the person's skeleton's, put on the exercise's as the offline analysis puts a
        recording (`analysis.kinematics.map_onto`, frame by frame)."""
        if self.skeleton is None:
            raise CameraFrameError("the person has not been in view yet")
        world = landmarks_of(values)
        own = np.vstack([self._frame(world[k]) for k in range(world.shape[0])])
        return map_onto(Motion(self.skeleton, own, 1.0 / self.fps), self.target).frames

    def keep(self, values: FloatArray) -> None:
        """Keep the landmarks of frames the session took, for the recording."""
        self.landmarks.extend(landmarks_of(values))

    def _frame(self, world: FloatArray) -> FloatArray:
        points = landmark_points(world[None])
        for name, track in points.items():
            if np.isfinite(track).all():
                self._last[name] = track
        missing = [name for name in REQUIRED if name not in self._last]
        if missing:
            raise CameraFrameError("the person is not yet in view: " + ", ".join(missing))
        held = {name: track * UNITS_PER_METRE for name, track in self._last.items()}
        return frame_values(held)

    def recording_json(self) -> bytes:
        """The landmarks taken, as a MediaPipe landmark file (``{"fps", "frames"}``: per frame
        33 ``{x, y, z, visibility}``, or an empty list where a landmark was not seen)."""
        frames = [_json_frame(world) for world in self.landmarks]
        return json.dumps({"fps": self.fps, "source": "camera", "frames": frames}).encode()


def frame_values(points: Mapping[str, FloatArray]) -> FloatArray:
    """The channel values (C,) of one frame of canonical points ({name: (1, 3) centimetres})."""
    usable = dict(points)
    complete(usable)
    rotations = global_rotations(usable, REST_DIRS)
    euler = quat.to_euler(local_quaternions(rotations, 1), EULER_ORDER)
    values = np.concatenate((usable["pelvis"][0], euler[0].reshape(-1)))
    if not np.isfinite(values).all():
        raise CaptureFileError("The landmarks do not form a body.")
    return values


def _json_frame(world: FloatArray) -> list[dict[str, float]]:
    """One frame for the file: every landmark, a hidden one at its last value with visibility 0
    (the file's reader drops it, as it drops MediaPipe's own unsure landmarks)."""
    out = []
    for k, _name in enumerate(MEDIAPIPE):
        x, y, z = (float(v) for v in world[k])
        if np.isfinite([x, y, z]).all():
            out.append({"x": round(x, 5), "y": round(y, 5), "z": round(z, 5), "visibility": 1.0})
        else:
            out.append({"x": 0.0, "y": 0.0, "z": 0.0, "visibility": 0.0})
    return out
