"""Each capture layout is parsed (`analysis.sources.read_recording`): the layout and kind are
named, the joints found and not used are listed, frame rate and units are read, gaps are bridged
and said, and a person standing reads near 0° at the hips, knees and shoulders."""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
import pytest

from analysis.kinematics import quaternions as quat
from analysis.kinematics.forward_kinematics import positions, rotations
from analysis.sources import CaptureFileError, motion_from_landmarks, read_recording
from analysis.sources.ik import NAMES, PELVIS_BACK, UNITS_PER_METRE, complete
from analysis.sources.names import MEDIAPIPE
from tests.capture_samples import LAYOUTS, kinect_long_csv, write_layout

FIXTURES = Path(__file__).parent / "fixtures" / "capture"
TRC = FIXTURES / "pose2sim_balancing.trc"
FPS = 30.0
KIND = {"kinect_wide": "kinect", "kinect_long": "kinect", "azure": "kinect", "trc": "trc",
        "c3d": "c3d", "mediapipe": "mediapipe"}  # fmt: skip


def standing(frames: int = 40, seed: int = 3) -> dict[str, np.ndarray]:
    """A person 1.7 m tall standing still facing +z (metres), with 3 mm of sensor noise."""
    rng = np.random.default_rng(seed)
    pose = {
        "pelvis": (0, 1.0, 0), "chest": (0, 1.45, 0), "neck": (0, 1.52, 0), "head": (0, 1.65, 0),
        "left_shoulder": (0.19, 1.42, 0), "right_shoulder": (-0.19, 1.42, 0),
        "left_elbow": (0.2, 1.12, 0), "right_elbow": (-0.2, 1.12, 0),
        "left_wrist": (0.2, 0.87, 0), "right_wrist": (-0.2, 0.87, 0),
        "left_hip": (0.1, 0.95, 0), "right_hip": (-0.1, 0.95, 0),
        "left_knee": (0.1, 0.52, 0), "right_knee": (-0.1, 0.52, 0),
        "left_ankle": (0.1, 0.09, 0), "right_ankle": (-0.1, 0.09, 0),
        "left_toe": (0.1, 0.02, 0.15), "right_toe": (-0.1, 0.02, 0.15),
    }  # fmt: skip
    return {
        k: np.array(v, float) + 0.003 * rng.standard_normal((frames, 3)) for k, v in pose.items()
    }


def local_angle(motion, joint: str) -> np.ndarray:
    """Degrees each frame's local rotation of ``joint`` turns away from the rest pose."""
    q = rotations(motion)[:, NAMES.index(joint)]
    return np.degrees(quat.angle_between(q, quat.identity(q.shape[:1])))


@pytest.mark.parametrize("layout", LAYOUTS)
def test_each_layout_is_read_with_its_kind_rate_and_joints(layout, tmp_path):
    path = write_layout(layout, standing(), FPS, tmp_path)
    recording = read_recording(path.name, path.read_bytes())
    assert recording.report.kind == KIND[layout]
    assert recording.source.kind == KIND[layout]
    assert recording.motion.n_frames == 40
    assert recording.motion.fps == pytest.approx(FPS, rel=1e-3)
    assert len(recording.report.joints_found) >= 14
    # written in m or mm: read back in the solver's centimetres, the person is 1.7 m tall
    height = positions(recording.motion)[:, NAMES.index("Head"), 1].mean() / UNITS_PER_METRE
    ankle = positions(recording.motion)[:, NAMES.index("LeftFoot"), 1].mean() / UNITS_PER_METRE
    assert height - ankle == pytest.approx(1.56, abs=0.05)


@pytest.mark.parametrize("layout", LAYOUTS)
@pytest.mark.parametrize(
    "joint", ["LeftUpperLeg", "RightUpperLeg", "LeftLowerLeg", "RightLowerLeg",
              "LeftUpperArm", "RightUpperArm"],
)  # fmt: skip
def test_a_standing_person_reads_near_zero_at_hips_knees_and_shoulders(layout, joint, tmp_path):
    path = write_layout(layout, standing(), FPS, tmp_path)
    motion = read_recording(path.name, path.read_bytes()).motion
    assert np.all(local_angle(motion, joint) < 10.0)


def test_a_raised_arm_reads_far_from_zero(tmp_path):
    """The standing check could pass with rotations stuck at zero: a raised arm must not."""
    points = standing()
    points["left_elbow"] = points["left_shoulder"] + (0.3, 0, 0)
    points["left_wrist"] = points["left_shoulder"] + (0.55, 0, 0)
    path = write_layout("kinect_wide", points, FPS, tmp_path)
    motion = read_recording(path.name, path.read_bytes()).motion
    assert np.all(np.abs(local_angle(motion, "LeftUpperArm") - 90.0) < 10.0)


def test_the_pose2sim_trc_imports_with_its_21_keypoints_named():
    recording = read_recording(TRC.name, TRC.read_bytes())
    report = recording.report
    assert report.kind == "trc"
    named = set(report.joints_found) | set(report.joints_unused)
    assert len(named) == 21
    assert {"RHip", "RKnee", "Neck", "Head", "Nose", "RShoulder", "LWrist"} <= named
    assert {"LHeel", "RSmallToe", "Nose"} <= set(report.joints_unused)
    assert recording.motion.n_frames == 100
    assert recording.motion.fps == pytest.approx(60.0)
    assert any("pelvis" in w for w in report.warnings)  # no Hip keypoint: estimated, and said


def test_a_c3d_written_by_ezc3d_round_trips(tmp_path):
    points = standing()
    path = write_layout("c3d", points, FPS, tmp_path)
    back = ezc3d.c3d(str(path))
    assert back["parameters"]["POINT"]["RATE"]["value"][0] == pytest.approx(FPS)
    motion = read_recording(path.name, path.read_bytes()).motion
    knee = positions(motion)[:, NAMES.index("LeftLowerLeg")] / UNITS_PER_METRE
    hip = positions(motion)[:, NAMES.index("LeftUpperLeg")] / UNITS_PER_METRE
    measured = np.linalg.norm(points["left_knee"] - points["left_hip"], axis=1)
    assert np.median(np.linalg.norm(knee - hip, axis=1)) == pytest.approx(
        np.median(measured), abs=0.005
    )


def plug_in_gait_markers(points: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Markers a lab would place on the standing person, the inverse of the documented rules."""
    p = points
    markers = {"LASI": p["pelvis"] + (0.12, 0.05, 0.08), "RASI": p["pelvis"] + (-0.12, 0.05, 0.08),
               "LPSI": p["pelvis"] + (0.05, 0.05, -0.1), "RPSI": p["pelvis"] + (-0.05, 0.05, -0.1),
               "CLAV": p["chest"] + (0, 0, 0.08), "C7": p["chest"] + (0, 0, -0.08),
               "LFHD": p["head"] + (0.05, 0, 0.08), "RFHD": p["head"] + (-0.05, 0, 0.08),
               "LBHD": p["head"] + (0.05, 0, -0.08),
               "RBHD": p["head"] + (-0.05, 0, -0.08)}  # fmt: skip
    for side, s, sign in (("left", "L", 1.0), ("right", "R", -1.0)):
        markers[f"{s}KNE"] = p[f"{side}_knee"] + (sign * 0.05, 0, 0)
        markers[f"{s}ANK"] = p[f"{side}_ankle"] + (sign * 0.035, 0, 0)
        markers[f"{s}TOE"] = p[f"{side}_toe"]
        markers[f"{s}SHO"] = p[f"{side}_shoulder"] + (0, 0.05, 0)
        markers[f"{s}ELB"] = p[f"{side}_elbow"]
        markers[f"{s}WRA"] = p[f"{side}_wrist"]
    return markers


def test_plug_in_gait_markers_become_joint_centres(tmp_path):
    markers = plug_in_gait_markers(standing())
    data = ezc3d.c3d()
    data["parameters"]["POINT"]["RATE"]["value"] = [FPS]
    data["parameters"]["POINT"]["LABELS"]["value"] = list(markers)
    data["parameters"]["POINT"]["UNITS"]["value"] = ["m"]
    values = np.ones((4, len(markers), 40))
    values[:3] = np.transpose(np.stack(list(markers.values()), axis=1), (2, 1, 0))
    data["data"]["points"] = values
    path = tmp_path / "lab.c3d"
    data.write(str(path))
    recording = read_recording(path.name, path.read_bytes())
    assert "Plug-in Gait" in recording.report.layout
    for joint in ("LeftUpperLeg", "LeftLowerLeg", "RightUpperArm"):
        assert np.all(local_angle(recording.motion, joint) < 10.0)


def test_gaps_are_bridged_and_said(tmp_path):
    points = standing()
    points["left_knee"][10:14] = np.nan
    path = tmp_path / "gaps.csv"
    text = kinect_long_csv(points, FPS).decode().replace("nan", "")
    path.write_text(text)
    recording = read_recording(path.name, path.read_bytes())
    assert any("left knee" in w and "4 frames" in w for w in recording.report.warnings)
    knee = positions(recording.motion)[:, NAMES.index("LeftLowerLeg")] / UNITS_PER_METRE
    assert np.all(np.isfinite(knee))
    assert np.abs(knee[10:14, 1] - 0.52).max() < 0.03


def test_landmarks_with_frames_without_a_person_are_bridged():
    world = np.zeros((20, len(MEDIAPIPE), 3))
    pose = standing(20)
    index = {n: k for k, n in enumerate(MEDIAPIPE)}
    for k, name in enumerate(MEDIAPIPE):
        side = "left" if name.startswith("left") else "right"
        key = name if name in pose else f"{side}_toe" if name.endswith("foot_index") else "head"
        world[:, k] = pose.get(key, pose["head"]) * (1, -1, -1)
    found = np.ones(20, bool)
    found[5:8] = False
    world[5:8] = 1e3  # whatever the estimator left there is not read
    solved = motion_from_landmarks(world, 25.0, found)
    assert solved.motion.fps == pytest.approx(25.0)
    assert solved.bridged and max(solved.bridged.values()) == 3
    assert index["left_hip"] == 23


def test_an_unknown_kind_of_file_is_refused_in_words():
    with pytest.raises(CaptureFileError, match="cannot be read; upload"):
        read_recording("take.xyz", b"1,2,3\n")


def trunk_estimates(points: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The points after `complete` fills in the trunk a source lacks."""
    filled = dict(points)
    complete(filled)
    return filled


def test_a_missing_pelvis_is_placed_behind_the_hip_joints():
    """Facing +z: the spine's base lies ``PELVIS_BACK`` hip widths behind the hip joints, not
    between them (the trunk line would lean forward by several degrees)."""
    points = standing()
    del points["pelvis"]
    pelvis = trunk_estimates(points)["pelvis"]
    hips = (points["left_hip"] + points["right_hip"]) / 2
    width = np.linalg.norm(points["left_hip"] - points["right_hip"], axis=1)
    assert np.allclose(hips[:, 2] - pelvis[:, 2], PELVIS_BACK * width, atol=0.005)
    assert np.allclose(pelvis[:, :2], hips[:, :2], atol=0.005)


def test_a_keypoint_sets_neck_is_the_top_of_the_chest():
    points = standing()
    del points["chest"]
    filled = trunk_estimates(points)
    assert np.array_equal(filled["chest"], points["neck"])
    assert np.all(filled["neck"][:, 1] > points["neck"][:, 1] + 0.03)  # re-placed up the neck


def test_without_chest_or_neck_the_chest_lies_under_the_head():
    """Shoulders uneven about the spine (the left one 6 cm further out): the chest follows the
    head, not the middle of the shoulders."""
    points = standing()
    del points["chest"], points["neck"]
    points["left_shoulder"] = points["left_shoulder"] + (0.06, 0.0, 0.0)
    chest = trunk_estimates(points)["chest"]
    assert np.all(np.abs(chest[:, 0] - np.median(points["head"][:, 0])) < 0.01)
    assert np.all(
        chest[:, 0] < (points["left_shoulder"][:, 0] + points["right_shoulder"][:, 0]) / 2 - 0.02
    )


def test_a_shoulder_the_recorder_puts_away_from_the_body_is_marked_lost_and_said(tmp_path):
    """A Kinect shoulder dropped 10 cm below its place (the tracker lost it) in frames 10–15 is
    marked lost there; a 3 cm shrug (the shoulder girdle moving) and the other side are not."""
    points = standing()
    points["left_shoulder"][10:16] += (0.0, -0.10, 0.0)
    points["left_shoulder"][20:26] += (0.0, 0.03, 0.0)
    path = write_layout("kinect_wide", points, FPS, tmp_path)
    recording = read_recording(path.name, path.read_bytes())
    assert set(recording.lost_frames) == {"left_shoulder"}
    assert np.flatnonzero(recording.lost_frames["left_shoulder"]).tolist() == list(range(10, 16))
    told = [w for w in recording.report.warnings if "shoulder" in w]
    assert told == [
        "The left shoulder was lost in 6 frames (the recorder placed it away from the body); "
        "those frames are left out of its angles."
    ]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_body_whose_shoulders_stay_in_place_marks_no_frame_lost(layout, tmp_path):
    path = write_layout(layout, standing(), FPS, tmp_path)
    recording = read_recording(path.name, path.read_bytes())
    assert recording.lost_frames == {}
    assert not any("was lost" in w for w in recording.report.warnings)
