"""One entry point for every capture file: `read_recording(name, content)`.

The kind is chosen by the file name's ending and checked against the content: ``.bvh``/``.bvh.gz``
(the BVH reader), ``.csv`` (Kinect joint positions, wide or long, with whatever other columns a
recorder adds, or without a header as the SDK dumps them; a long file of MediaPipe landmark names
or numbers is read as MediaPipe), ``.txt`` (a Kinect SDK dump, or Vicon ART target text by its 119
values a line), ``.json`` (Azure Kinect Body Tracking when its frames hold ``bodies``; BlazePose
keyed by frame and landmark name under ``positions``; else MediaPipe landmarks), ``.trc`` and
``.c3d``. Positions go through
`analysis.sources.ik`; unreadable input raises `CaptureFileError` (a `BVHError`) in one sentence.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.bvh.io import Motion, read
from analysis.sources import blazepose, kinect, kinect_text, markers, mediapipe, vicon
from analysis.sources.c3d import read_c3d
from analysis.sources.errors import CaptureFileError
from analysis.sources.ik import PLAIN, Solved, solve
from analysis.sources.names import KINECT_V2, MEDIAPIPE
from analysis.sources.report import ImportedRecording, ImportReport
from analysis.sources.tables import DEFAULT_FPS, FloatArray, csv_rows, to_metres, z_up_to_y_up
from analysis.sources.trc import read_trc
from analysis.sources.video import SUFFIXES as VIDEO_SUFFIXES
from analysis.sources.video import Progress, read_video_bytes

BVH_SUFFIXES = (".bvh", ".bvh.gz")
SUFFIXES = (*BVH_SUFFIXES, ".csv", ".txt", ".json", ".trc", ".c3d", *VIDEO_SUFFIXES)
WHAT = (
    "a .bvh, .bvh.gz, .csv or .txt (Kinect, Vicon), .json (Azure Kinect, BlazePose or "
    "MediaPipe), .trc or .c3d file, or a video (.mp4, .mov, .webm)"
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
        (".csv", _csv), (".txt", _text), (".json", _json), (".trc", _trc), (".c3d", _c3d),
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
    empty: np.ndarray | None = None  # frames in which the recorder found no body at all


def _imported(found: Found) -> ImportedRecording:
    """Solve the canonical points and report, in words, what was bridged or assumed."""
    kind, layout, points, fps = found.kind, found.layout, found.points, found.fps
    used, unused, notes = found.used, found.unused, list(found.notes)
    if fps is None:
        fps = DEFAULT_FPS
        notes.append(f"The file gives no times; {DEFAULT_FPS:g} frames per second was assumed.")
    solved = solve(points, fps)
    notes.extend(_gap_notes(solved, int(found.empty.sum()) if found.empty is not None else 0))
    notes.extend(_lost_notes(solved))
    report = ImportReport(kind, layout, tuple(used), tuple(unused), tuple(notes))
    return ImportedRecording(_with_warnings(solved.motion, report.warnings), report, solved.lost)


def _with_warnings(motion: Motion, warnings: tuple[str, ...]) -> Motion:
    return Motion(motion.skeleton, motion.frames, motion.frame_time, warnings)


def _lost_notes(solved: Solved) -> list[str]:
    """A note per joint the recorder lost (placed away from where the body carries it)."""
    return [
        f"The {name.replace('_', ' ')} was lost in {int(frames.sum())} frames (the recorder "
        "placed it away from the body); those frames are left out of its angles."
        for name, frames in solved.lost.items()
    ]


def _gap_notes(solved: Solved, empty: int = 0) -> list[str]:
    """Notes on points bridged, beyond the ``empty`` frames without a body (told once)."""
    more = " more" if empty else ""
    notes = [
        f"The {name.replace('_', ' ')} was not seen in {n - empty}{more} frames; those were "
        "filled in from the frames around them."
        for name, n in solved.bridged.items()
        if n > empty
    ]
    if solved.estimated:
        shown = ", ".join(PLAIN.get(e, e.replace("_", " ")) for e in solved.estimated)
        notes.append(
            f"The file has no point for the {shown}; each was estimated from the points around it."
        )
    return notes


def _csv(content: bytes) -> ImportedRecording:
    head = content[:4096].decode("utf-8", "replace").splitlines()
    if kinect_text.is_numeric_line(next((line for line in head if line.strip()), "")):
        return _text(content)  # a dump without a header (leading empty lines: no body yet)
    rows = csv_rows(content)
    cols = kinect_text.per_joint_columns(rows[0])
    if cols is not None and ("state" in cols or kinect.long_columns(rows[0]) is None):
        tracks, fps, tracking = kinect_text.read_per_joint(rows)
        tracks = _numbered(tracks)
        layout = "Kinect joint positions, one row per joint per frame, with the recorder's columns"
        return _tracked(tracks, fps, tracking, layout)
    if kinect.long_columns(rows[0]) is not None:
        tracks, fps, _names, seen = kinect.read_long(rows, MEDIAPIPE)
        if set(tracks) <= set(MEDIAPIPE):
            world = mediapipe.landmarks_from_tracks(tracks, seen)
            return _landmarks(world, fps, "MediaPipe landmarks, one row per landmark per frame")
        return _kinect(tracks, fps, "Kinect joint positions, one row per joint per frame")
    tracks, fps, _names = kinect.read_wide(rows)
    return _kinect(tracks, fps, "Kinect joint positions, one row per frame")


def _kinect(
    tracks: dict[str, FloatArray], fps: float | None, layout: str,
    notes: tuple[str, ...] = (), empty: np.ndarray | None = None,
) -> ImportedRecording:  # fmt: skip
    points, used, unused = kinect.to_canonical(tracks)
    points, unit = to_metres(points, None)
    told = [*notes, *([] if unit == "m" else [f"The positions were read as {unit}."])]
    return _imported(Found("kinect", layout, points, fps, used, unused, told, empty))


def _numbered(tracks: dict[str, FloatArray]) -> dict[str, FloatArray]:
    """Joint numbers (the SDK's JointType 0–24) as the SDK's joint names."""
    if not all(name.isdigit() and int(name) < len(KINECT_V2) for name in tracks):
        return tracks
    return {KINECT_V2[int(name)]: track for name, track in tracks.items()}


def _tracked(
    tracks: dict[str, FloatArray], fps: float | None, tracking: kinect_text.Tracking, layout: str
) -> ImportedRecording:
    """Kinect tracks with the sensor's tracking: frames without a body told once; inferred
    positions in short runs filled in from tracked frames, longer runs kept (and said)."""
    if tracking.empty.all():
        raise CaptureFileError("No body was tracked in any frame of the file.")
    tracks, filled, kept = kinect_text.bridge_inferred(tracks, tracking)
    notes = []
    if tracking.empty.any():
        notes.append(
            f"No body was tracked in {int(tracking.empty.sum())} frames; they were filled in "
            "from the frames around them."
        )
    if filled or kept:
        notes.append(
            f"The Kinect only inferred {filled + kept} joint positions (it did not see them): "
            f"{filled} in short runs were filled in from the frames where it saw the joint, "
            f"{kept} in longer runs were kept as inferred."
        )
    return _kinect(tracks, fps, layout, tuple(notes), tracking.empty)


def _text(content: bytes) -> ImportedRecording:
    """A text file of numbers without a header: Vicon ART targets or a Kinect SDK dump."""
    rows = kinect_text.numeric_rows(content)
    if kinect_text.frame_width(rows) == vicon.WIDTH:
        return _vicon(rows)
    tracks, fps, tracking, layout = kinect_text.read_dump(rows)
    return _tracked(tracks, fps, tracking, layout)


def _vicon(rows: list[list[float] | None]) -> ImportedRecording:
    targets, swapped = vicon.in_chain_order(vicon.read_targets(rows))
    points, _unit = to_metres(vicon.joint_centres(targets), None)
    notes = [
        f"The file gives no times; the targets' usual {vicon.ART_FPS:g} frames per second was "
        "assumed.",
        *swapped,
        "Joint centres were found as the points that move with both targets they join.",
    ]
    layout = "Vicon ART target text, 17 targets × position and orientation per line"
    used = list(vicon.TARGETS)
    return _imported(Found("vicon", layout, points, vicon.ART_FPS, used, [], notes))


def _landmarks(
    world: FloatArray, fps: float | None, layout: str, kind: str = "mediapipe"
) -> ImportedRecording:
    solved = mediapipe.motion_from_landmarks(world, fps or DEFAULT_FPS, smoothing=1)
    hidden = int(np.sum(np.all(np.isnan(world), axis=(1, 2))))
    notes = _gap_notes(solved)
    if hidden:
        notes.insert(0, f"No person was found in {hidden} frames; they were filled in.")
    used = tuple(MEDIAPIPE)
    report = ImportReport(kind, layout, used, (), tuple(notes))
    return ImportedRecording(_with_warnings(solved.motion, report.warnings), report)


def _json(content: bytes) -> ImportedRecording:
    data = kinect.load_json(content)
    frames = data.get("frames") if isinstance(data, dict) else None
    if isinstance(frames, list) and any(isinstance(f, dict) and "bodies" in f for f in frames):
        tracks, fps, _names = kinect.read_azure(data)
        return _kinect(tracks, fps, "Azure Kinect body tracking JSON")
    if blazepose.is_keyed(data):
        return _keyed(blazepose.read_keyed(data))
    world, fps = mediapipe.landmarks_from_json(data)
    if isinstance(data, dict) and data.get("source") == "camera":  # the camera page's session
        return _landmarks(world, fps, "landmarks from the browser camera", kind="camera")
    return _landmarks(world, fps, "MediaPipe landmarks JSON")


def _keyed(found: blazepose.KeyedLandmarks) -> ImportedRecording:
    solved = mediapipe.motion_from_landmarks(found.world, found.fps, smoothing=1)
    empty = int(np.sum(np.all(np.isnan(found.world), axis=(1, 2))))
    notes = (*found.notes, *_gap_notes(solved, empty))
    layout = "BlazePose landmarks JSON keyed by frame and landmark name"
    report = ImportReport("mediapipe", layout, tuple(MEDIAPIPE), (), notes)
    return ImportedRecording(_with_warnings(solved.motion, report.warnings), report)


def _named(tracks: Mapping[str, FloatArray], unit: str | None, kind: str, layout: str,
           fps: float) -> ImportedRecording:  # fmt: skip
    """Marker or keypoint tracks: Plug-in Gait markers → joint centres, else keypoint names."""
    tracks, _unit = to_metres(dict(tracks), unit)
    if markers.is_plug_in_gait(set(tracks)):
        points = z_up_to_y_up(markers.joint_centres(tracks))
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
