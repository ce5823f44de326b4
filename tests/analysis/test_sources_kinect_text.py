"""Kinect files as recorders write them, written here from their descriptions (not by the
product's writers): the per-joint CSV with a data set's own columns, and the SDK's headerless
dump (25 joints × 3, 4 or 7 values a line; comma or space separated; trailing separators; empty
lines where no body was tracked). Also: the minimum length is stated truthfully."""

from __future__ import annotations

import re

import numpy as np
import pytest

from analysis.bvh import RecordingTooShortError
from analysis.kinematics.forward_kinematics import positions
from analysis.pipeline.prepare import check_length
from analysis.sources import CaptureFileError, read_recording
from analysis.sources.ik import JOINTS, UNITS_PER_METRE

FRAMES = 60
# The SDK's 25 joints in its order, standing (metres, camera space: y up, facing the camera).
KINECT = {
    "SpineBase": (0, 1.0, 2.5), "SpineMid": (0, 1.22, 2.5), "Neck": (0, 1.52, 2.5),
    "Head": (0, 1.65, 2.5), "ShoulderLeft": (0.19, 1.42, 2.5), "ElbowLeft": (0.2, 1.12, 2.5),
    "WristLeft": (0.2, 0.87, 2.5), "HandLeft": (0.2, 0.8, 2.5), "ShoulderRight": (-0.19, 1.42, 2.5),
    "ElbowRight": (-0.2, 1.12, 2.5), "WristRight": (-0.2, 0.87, 2.5), "HandRight": (-0.2, 0.8, 2.5),
    "HipLeft": (0.1, 0.95, 2.5), "KneeLeft": (0.1, 0.52, 2.5), "AnkleLeft": (0.1, 0.09, 2.5),
    "FootLeft": (0.1, 0.02, 2.35), "HipRight": (-0.1, 0.95, 2.5), "KneeRight": (-0.1, 0.52, 2.5),
    "AnkleRight": (-0.1, 0.09, 2.5), "FootRight": (-0.1, 0.02, 2.35),
    "SpineShoulder": (0, 1.45, 2.5), "HandTipLeft": (0.2, 0.72, 2.5), "ThumbLeft": (0.17, 0.8, 2.5),
    "HandTipRight": (-0.2, 0.72, 2.5), "ThumbRight": (-0.17, 0.8, 2.5),
}  # fmt: skip
NAMES = list(KINECT)


def elbow_bend(t: np.ndarray) -> np.ndarray:
    """Degrees the left elbow bends over the take: 0 → 90 → 0."""
    return 90.0 * np.sin(np.pi * t / (FRAMES - 1))


def frames() -> np.ndarray:
    """(FRAMES, 25, 3) positions: standing, the left forearm bending forward (towards −z, the
    camera) and back."""
    out = np.tile(np.array([KINECT[n] for n in NAMES], dtype=float), (FRAMES, 1, 1))
    bend = np.radians(elbow_bend(np.arange(FRAMES)))
    elbow = out[:, NAMES.index("ElbowLeft")]
    for name, length in (("WristLeft", 0.25), ("HandLeft", 0.32), ("HandTipLeft", 0.40),
                         ("ThumbLeft", 0.32)):  # fmt: skip
        k = NAMES.index(name)
        out[:, k, 1] = elbow[:, 1] - length * np.cos(bend)
        out[:, k, 2] = elbow[:, 2] - length * np.sin(bend)
    return out


def left_elbow_angle(motion) -> np.ndarray:
    at = positions(motion) / UNITS_PER_METRE
    point = {row[2]: at[:, j] for j, row in enumerate(JOINTS)}
    u = point["left_shoulder"] - point["left_elbow"]
    v = point["left_wrist"] - point["left_elbow"]
    cos = np.sum(u * v, 1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
    return 180.0 - np.degrees(np.arccos(np.clip(cos, -1, 1)))


def test_the_per_joint_csv_with_a_data_sets_own_columns_is_read():
    header = (
        "SubjectID, DateID, GestureLabel, RepetitionNumber, CorrectLabel, Position, Timestamp1, "
        "Timestamp2, Timestamp3, JointName, TrackingStatus, X, Y, Z, X_proj, Y_proj"
    )
    lines = [header]
    data = frames()
    for f in range(FRAMES):
        ticks = 130_000_000 + f * 333_333  # 100 ns ticks, 30 fps
        for k, name in enumerate(NAMES):
            state = "Inferred" if name == "KneeRight" and 10 <= f < 14 else "Tracked"
            x, y, z = data[f, k]
            lines.append(f"205, 2017-11-02, 3, 1, 1, Stand, {ticks}, 0, 0, {name}, {state}, "
                         f"{x:.4f}, {y:.4f}, {z:.4f}, {300 + x:.1f}, {200 + y:.1f}")  # fmt: skip
    imported = read_recording("take.csv", "\n".join(lines).encode())
    report = imported.report
    assert report.kind == "kinect" and "one row per joint per frame" in report.layout
    assert imported.motion.n_frames == FRAMES and abs(imported.motion.fps - 30.0) < 0.1
    assert "KneeRight" in report.joints_found
    assert any("only inferred 4 joint positions" in w for w in report.warnings), report.warnings
    assert np.abs(left_elbow_angle(imported.motion) - elbow_bend(np.arange(FRAMES))).max() < 3.0


def dump(values_per_joint: int, separator: str, trailing: str) -> str:
    """The SDK's dump: a line per frame, frames 20–24 empty (no body tracked)."""
    data = frames()
    lines = []
    for f in range(FRAMES):
        if 20 <= f < 25:
            lines.append("")
            continue
        cells = []
        for k in range(len(NAMES)):
            cells += [f"{v:.5f}" for v in data[f, k]]
            if values_per_joint == 4:
                cells.append("1" if (NAMES[k] == "KneeLeft" and f < 3) else "2")
            elif values_per_joint == 7:
                cells += ["0", "0", "0", "1"]
        lines.append(separator.join(cells) + trailing)
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    ("per", "separator", "trailing", "name"),
    [(4, ",", ",", "body.csv"), (3, " ", " ", "body.txt"), (7, " ", "", "kinect.txt"),
     (4, "\t", "", "dump.txt")],
)  # fmt: skip
def test_the_sdks_dump_without_a_header_is_read(per, separator, trailing, name):
    imported = read_recording(name, ("\n" + dump(per, separator, trailing)).encode())
    report = imported.report
    assert report.kind == "kinect" and "without a header" in report.layout
    assert imported.motion.n_frames == FRAMES + 1  # the leading empty line: no body yet
    assert any("No body was tracked in 6 frames" in w for w in report.warnings), report.warnings
    if per == 4:
        assert any("only inferred 3 joint positions" in w for w in report.warnings)
    bend = elbow_bend(np.arange(FRAMES))
    seen = np.r_[0:20, 25:FRAMES]
    assert np.abs(left_elbow_angle(imported.motion)[1:][seen] - bend[seen]).max() < 3.0


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("1 2 3\n4 5 6\n", "25 joints of 3, 4 or 7 values"),
        ("JointName,X,Y\nHead,1,2\nHead,1,2\n", "No joint position columns"),
        (dump(4, ",", ",").replace(",2,", ",7,", 1), "tracking state"),
    ],
)
def test_what_cannot_be_read_names_what_is_missing_in_one_line(text, words):
    with pytest.raises(CaptureFileError, match=words) as caught:
        read_recording("take.csv", text.encode())
    assert "\n" not in str(caught.value)


def test_a_19_frame_take_is_accepted_when_it_can_hold_a_repetition_or_told_the_truth():
    motion = read_recording("take.txt", dump(3, " ", "").encode()).motion
    short = motion.with_frames(motion.frames[:19])  # 19 frames at 30 fps: 0.633 s
    check_length(short, rep_frames=38.0, model_fps=30.0)  # the bar is exactly 19 frames
    with pytest.raises(RecordingTooShortError) as caught:
        check_length(short, rep_frames=39.0, model_fps=30.0)
    message = str(caught.value)
    lasts, frames_had, least, frames_needed = re.search(
        r"lasts ([\d.]+ s) \((\d+) frames\); at least ([\d.]+ s) \((\d+) frames\)", message
    ).groups()
    assert lasts != least and float(lasts[:-2]) < float(least[:-2]), message
    assert (frames_had, frames_needed) == ("19", "20")


ZEROS = (" ".join(["0"] * 175) + "\n") * 3
HOSTILE = {
    "zeros.txt": (ZEROS, "No body was tracked in any frame"),
    "keys.json": ('{"positions": {"x": {}}}', "frame key 'x' is not a number"),
    "frame.json": ('{"positions": {"1": 5, "2": {}}}', "Frame 1 of the JSON is not an object"),
    "far.json": ('{"positions": {"1e300": {}, "2": {}}}', "too far apart"),
    "nohips.json": ('{"positions": {"1": {"Nose": [0.5, 0.5, 0]}, "2": {}}}', "no hips"),
    "state.csv": ("JointName,X,Y,Z,TrackingState\nHead,1,2,3,Weird\n", "tracking state"),
    "short.txt": ("1 2 3\n4 5 6\n", "25 joints of 3, 4 or 7 values"),
    "vicon.txt": ((" ".join(["1"] * 119) + "\n") * 3 + " ".join(["1"] * 118), "17 targets × 7"),
}


@pytest.mark.parametrize("name", HOSTILE)
def test_broken_recorder_files_are_refused_in_one_sentence(name):
    text, words = HOSTILE[name]
    with pytest.raises(CaptureFileError, match=words) as caught:
        read_recording(name, text.encode())
    assert "\n" not in str(caught.value)
