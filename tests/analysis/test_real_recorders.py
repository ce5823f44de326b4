"""The KERAAL samples (tests/analysis/fixtures/keraal/, BSD-2-Clause): one seated take of each of
three low-back-pain exercises recorded at once by a Kinect v2 (SDK dump), by BlazePose on the
video (image coordinates, mirrored frames, frames without a person left out) and by Vicon ART
targets, each in its recorder's own format. Every file is read by content; an exercise made from
the Kinect take counts the same repetitions in the Vicon take, and in BlazePose's where the
camera shows the movement's plane (docs/CAPTURE_SOURCES.md).

Not yet met (issue 35, measured and reported): Vicon counts one repetition of ELK where the
Kinect counts two, and the shoulder elevation's peak in CTK reads 14–17° lower from Vicon's
joint centres than from the Kinect's; those are not asserted here."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import pytest

from analysis.landmarks import suggest_key_poses
from analysis.pipeline.model import build_model
from analysis.pipeline.run import analyse
from analysis.sources import read_recording

KERAAL = Path(__file__).parent / "fixtures" / "keraal"
EXERCISES = ("CTK", "ELK", "RTK")
VICON_COUNTED = ("CTK", "RTK")


def imported(recorder: str, exercise: str):
    path = next(KERAAL.glob(f"G3-{recorder}-{exercise}-*"))
    return read_recording(path.name, path.read_bytes())


@cache
def kinect_model(exercise: str):
    reference = imported("Kinect", exercise).motion
    poses = suggest_key_poses(reference)
    return build_model(reference, poses.frames.tolist(), poses.types.tolist())


@cache
def summary(recorder: str, exercise: str):
    return analyse(imported(recorder, exercise).motion, kinect_model(exercise)).summary


def count(recorder: str, exercise: str) -> int:
    return summary(recorder, exercise).repetition_count


@pytest.mark.parametrize("exercise", EXERCISES)
def test_each_recorders_own_file_is_read_by_content(exercise):
    kinect, blazepose, vicon = (imported(r, exercise) for r in ("Kinect", "BP", "Vicon"))
    assert kinect.report.kind == "kinect" and "25 joints × x, y, z and orientation" in (
        kinect.report.layout
    )
    assert vicon.report.kind == "vicon" and vicon.motion.n_frames > 380
    assert blazepose.report.kind == "mediapipe"
    notes = " ".join(blazepose.report.warnings)
    assert "mirrored picture" in notes and "picture coordinates" in notes and "16:9" in notes
    # Frames are the keys' numbers: the take lasts as long as the Kinect's (30 fps both).
    assert abs(blazepose.motion.n_frames - kinect.motion.n_frames) <= 4


@pytest.mark.parametrize("exercise", VICON_COUNTED)
def test_vicon_counts_the_repetitions_the_kinect_counts(exercise):
    assert count("Kinect", exercise) >= 1
    assert count("Vicon", exercise) == count("Kinect", exercise)


@pytest.mark.parametrize("exercise", EXERCISES)
def test_blazepose_counts_the_repetitions_the_kinect_counts(exercise):
    assert count("BP", exercise) == count("Kinect", exercise)


def test_blazepose_reads_the_sideways_bend_the_camera_sees_like_the_kinect():
    """ELK trains bending sideways, in the picture's plane: within 15° at both ends."""
    kinect = summary("Kinect", "ELK").clinical_angles["trunk_lateral_flexion"]
    seen = summary("BP", "ELK").clinical_angles["trunk_lateral_flexion"]
    assert kinect.max - kinect.min > 40.0  # the bend is there to compare
    assert abs(seen.min - kinect.min) <= 15.0 and abs(seen.max - kinect.max) <= 15.0


def test_mirrored_blazepose_is_put_back_on_the_right_side():
    """In ELK the person first bends to one side with the opposite arm over the head: the arm
    raised first is the same in the Kinect's take and in BlazePose's once mirrored back."""
    first = {}
    for recorder in ("Kinect", "BP"):
        angles = summary(recorder, "ELK").repetitions[0].clinical_angles
        peaks = {side: angles[f"shoulder_elevation_{side}"].max for side in ("left", "right")}
        first[recorder] = max(peaks, key=peaks.get)
    assert first["Kinect"] == first["BP"]
