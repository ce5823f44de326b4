"""One entry point for every capture file: `read_recording(name, content)`.

The kind is chosen by the file name's ending and checked against the content: ``.bvh``/``.bvh.gz``
(the BVH reader), ``.csv`` (Kinect joint positions, wide or long; a long file of MediaPipe
landmark names or numbers is read as MediaPipe), ``.json`` (Azure Kinect Body Tracking when its
frames hold ``bodies``, else MediaPipe landmarks), ``.trc`` and ``.c3d``. Positions go through
`analysis.sources.ik`; unreadable input raises `CaptureFileError` (a `BVHError`) in one sentence.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.bvh.io import Motion, read
from analysis.sources import kinect, markers, mediapipe
from analysis.sources.c3d import read_c3d
from analysis.sources.errors import CaptureFileError
from analysis.sources.ik import PLAIN, Solved, solve
from analysis.sources.names import MEDIAPIPE
from analysis.sources.report import ImportedRecording, ImportReport
from analysis.sources.tables import DEFAULT_FPS, FloatArray, csv_rows, to_metres
from analysis.sources.trc import read_trc
from analysis.sources.video import SUFFIXES as VIDEO_SUFFIXES
from analysis.sources.video import Progress, read_video_bytes

BVH_SUFFIXES = (".bvh", ".bvh.gz")
SUFFIXES = (*BVH_SUFFIXES, ".csv", ".json", ".trc", ".c3d", *VIDEO_SUFFIXES)
WHAT = (
    "a .bvh, .bvh.gz, .csv (Kinect), .json (Azure Kinect or MediaPipe), .trc or .c3d file, "
    "or a video (.mp4, .mov, .webm)"
)


def read_recording(
    name: str, content: bytes, progress: Progress | None = None, **bvh_options: Any
) -> ImportedRecording:
    """The recording in ``content`` (file ``name``); ``bvh_options`` go to `analysis.bvh.read`;
    ``progress`` hears the share of a video's frames read (other files read at once)."""
    lower = name.lower()
    video = next((s for s in VIDEO_SUFFIXES if lower.endswith(s)), None)
    if video is not None:
        return read_video_bytes(content, video, progress)
    if lower.endswith(BVH_SUFFIXES) or content[:9] == b"HIERARCHY":
        motion = read(content, **bvh_options)
        joints = tuple(motion.skeleton.names)
        return ImportedRecording(motion, ImportReport("bvh", "BVH", joints, (), motion.warnings))
    if not content.strip():
        raise CaptureFileError("The file is empty.")
    for suffix, reader in (
        (".csv", _csv), (".json", _json), (".trc", _trc), (".c3d", _c3d),
    ):  # fmt: skip
        if lower.endswith(suffix):
            return _guarded(reader, content)
    raise CaptureFileError(f"This kind of file cannot be read; upload {WHAT}.")


def _guarded(reader: Callable[[bytes], ImportedRecording], content: bytes) -> ImportedRecording:
    """The importer's result; a numeric failure the checks did not foresee (a number too large
    for a float, a shape numpy refuses) becomes the same one-line error, never a traceback."""
    try:
        return reader(content)
    except CaptureFileError:
        raise
    except (ArithmeticError, ValueError, TypeError, IndexError, KeyError) as error:
        kind = error.__class__.__name__
        raise CaptureFileError(f"The file's values cannot be used ({kind}).") from None


@dataclass(frozen=True)
class Found:
    """What an importer read: canonical points, the frame rate (None: not in the file), the
    file's names used and not used, and notes so far."""

    kind: str
    layout: str
    points: dict[str, FloatArray]
    fps: float | None
    used: list[str]
    unused: list[str]
    notes: list[str]


def _imported(found: Found) -> ImportedRecording:
    """Solve the canonical points and report, in words, what was bridged or assumed."""
    kind, layout, points, fps = found.kind, found.layout, found.points, found.fps
    used, unused, notes = found.used, found.unused, list(found.notes)
    if fps is None:
        fps = DEFAULT_FPS
        notes.append(f"The file gives no times; {DEFAULT_FPS:g} frames per second was assumed.")
    solved = solve(points, fps)
    notes.extend(_gap_notes(solved))
    report = ImportReport(kind, layout, tuple(used), tuple(unused), tuple(notes))
    return ImportedRecording(_with_warnings(solved.motion, report.warnings), report)


def _with_warnings(motion: Motion, warnings: tuple[str, ...]) -> Motion:
    return Motion(motion.skeleton, motion.frames, motion.frame_time, warnings)


def _gap_notes(solved: Solved) -> list[str]:
    notes = [
        f"The {name.replace('_', ' ')} was not seen in {n} frames; those were filled in "
        "from the frames around them."
        for name, n in solved.bridged.items()
    ]
    if solved.estimated:
        shown = ", ".join(PLAIN.get(e, e.replace("_", " ")) for e in solved.estimated)
        notes.append(
            f"The file has no point for the {shown}; each was estimated from the points around it."
        )
    return notes


def _csv(content: bytes) -> ImportedRecording:
    rows = csv_rows(content)
    if kinect.long_columns(rows[0]) is not None:
        tracks, fps, _names, seen = kinect.read_long(rows, MEDIAPIPE)
        if set(tracks) <= set(MEDIAPIPE):
            world = mediapipe.landmarks_from_tracks(tracks, seen)
            return _landmarks(world, fps, "MediaPipe landmarks, one row per landmark per frame")
        return _kinect(tracks, fps, "Kinect joint positions, one row per joint per frame")
    tracks, fps, _names = kinect.read_wide(rows)
    return _kinect(tracks, fps, "Kinect joint positions, one row per frame")


def _kinect(tracks: dict[str, FloatArray], fps: float | None, layout: str) -> ImportedRecording:
    points, used, unused = kinect.to_canonical(tracks)
    points, unit = to_metres(points, None)
    notes = [] if unit == "m" else [f"The positions were read as {unit}."]
    return _imported(Found("kinect", layout, points, fps, used, unused, notes))


def _landmarks(world: FloatArray, fps: float | None, layout: str) -> ImportedRecording:
    solved = mediapipe.motion_from_landmarks(world, fps or DEFAULT_FPS, smoothing=1)
    hidden = int(np.sum(np.all(np.isnan(world), axis=(1, 2))))
    notes = _gap_notes(solved)
    if hidden:
        notes.insert(0, f"No person was found in {hidden} frames; they were filled in.")
    used = tuple(MEDIAPIPE)
    report = ImportReport("mediapipe", layout, used, (), tuple(notes))
    return ImportedRecording(_with_warnings(solved.motion, report.warnings), report)


def _json(content: bytes) -> ImportedRecording:
    data = kinect.load_json(content)
    frames = data.get("frames") if isinstance(data, dict) else None
    if isinstance(frames, list) and any(isinstance(f, dict) and "bodies" in f for f in frames):
        tracks, fps, _names = kinect.read_azure(data)
        return _kinect(tracks, fps, "Azure Kinect body tracking JSON")
    world, fps = mediapipe.landmarks_from_json(data)
    return _landmarks(world, fps, "MediaPipe landmarks JSON")


def _named(tracks: Mapping[str, FloatArray], unit: str | None, kind: str, layout: str,
           fps: float) -> ImportedRecording:  # fmt: skip
    """Marker or keypoint tracks: Plug-in Gait markers → joint centres, else keypoint names."""
    tracks, _unit = to_metres(dict(tracks), unit)
    if markers.is_plug_in_gait(set(tracks)):
        points = markers.joint_centres(tracks)
        note = "Joint centres were estimated from Plug-in Gait skin markers."
        layout += ", Plug-in Gait markers"
        return _imported(Found(kind, layout, points, fps, list(tracks), [], [note]))
    points, used, unused = kinect.to_canonical(tracks)
    return _imported(Found(kind, layout, points, fps, used, unused, []))


def _trc(content: bytes) -> ImportedRecording:
    tracks, fps, unit = read_trc(content)
    return _named(tracks, unit, "trc", "TRC marker file", fps)


def _c3d(content: bytes) -> ImportedRecording:
    tracks, fps, unit = read_c3d(content)
    return _named(tracks, unit, "c3d", "C3D marker file", fps)
