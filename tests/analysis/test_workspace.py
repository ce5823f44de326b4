"""Reachable workspace: known sphere caps (points and a posed arm), quadrants, degenerate paths."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import read
from analysis.clinical import QUADRANTS, reachable_workspace, workspace_from_points
from tests.synthetic_poses import posed, rot

UI_PRMD = Path(__file__).resolve().parents[2] / "data" / "ui-prmd" / "sessions"


def cap(axis: np.ndarray, half_angle: float, n_rings: int = 12, n_around: int = 90) -> np.ndarray:
    """Unit directions filling a spherical cap (its rim densely) around ``axis``."""
    axis = axis / np.linalg.norm(axis)
    helper = np.array([0.0, 1.0, 0.0]) if abs(axis[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    polar = np.radians(np.linspace(0.0, half_angle, n_rings))[:, None]
    around = np.linspace(0.0, 2 * np.pi, n_around, endpoint=False)[None, :]
    points = (
        np.cos(polar)[..., None] * axis
        + (np.sin(polar) * np.cos(around))[..., None] * u
        + (np.sin(polar) * np.sin(around))[..., None] * v
    )
    return points.reshape(-1, 3)


def cap_share(half_angle: float) -> float:
    """Area of a cap over the hemisphere's: 2π(1 − cos a) / 2π."""
    return 1.0 - np.cos(np.radians(half_angle))


@pytest.mark.parametrize("half_angle", [30.0, 60.0, 85.0])
def test_cap_in_front_of_the_shoulder(half_angle):
    reach = 0.9 * cap(np.array([1.0, 0.0, 0.0]), half_angle)  # the hand short of full reach
    ws = workspace_from_points(reach, "right")
    assert ws.relative_area == pytest.approx(cap_share(half_angle), rel=0.05)
    # Centred on the anterior axis: the four quadrants share it equally.
    for name in QUADRANTS:
        assert ws.quadrants[name] == pytest.approx(ws.relative_area / 4, rel=0.05)
    assert sum(ws.quadrants.values()) == pytest.approx(ws.relative_area, abs=1e-3)
    assert np.allclose(np.linalg.norm(ws.vertices, axis=1), 1.0)
    assert ws.faces.max() < len(ws.vertices)


def test_cap_above_and_out_lands_in_the_upper_lateral_quadrant():
    axis = np.array([1.0, 1.0, 1.0])  # forward, up and out
    ws = workspace_from_points(cap(axis, 20.0), "left")
    assert ws.relative_area == pytest.approx(cap_share(20.0), rel=0.05)
    assert ws.quadrants["upper_lateral"] == pytest.approx(ws.relative_area, rel=1e-3)


def test_only_the_frontal_hemisphere_counts():
    ws = workspace_from_points(cap(np.array([0.0, 0.0, 1.0]), 40.0), "right")  # straight out
    assert ws.relative_area == pytest.approx(cap_share(40.0) / 2, rel=0.05)


def test_hand_path_of_a_posed_arm():
    """The right arm (T-pose rest along −x) swept through a 45° cap around straight forward."""
    directions = cap(np.array([0.0, 0.0, 1.0]), 45.0, n_rings=6, n_around=40)
    rest = np.array([-1.0, 0.0, 0.0])
    poses = []
    for d in directions:
        axis = np.cross(rest, d)
        angle = np.degrees(np.arccos(np.clip(rest @ d, -1, 1)))
        turn = rot("x", 0.0) if np.linalg.norm(axis) < 1e-9 else _about(axis, angle)
        poses.append({"RightUpperArm": turn})
    ws = reachable_workspace(posed(poses))
    assert set(ws) == {"left", "right"}
    assert ws["right"].relative_area == pytest.approx(cap_share(45.0), rel=0.05)
    assert ws["right"].arm_length == pytest.approx(53.0)
    assert ws["left"].relative_area == 0.0  # the left arm hangs still
    one = reachable_workspace(posed(poses), start=0, end=0)["right"]
    assert one.relative_area == 0.0


def _about(axis: np.ndarray, degrees: float) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_rotvec(np.radians(degrees) * axis / np.linalg.norm(axis)).as_matrix()


def test_degenerate_paths_have_no_area():
    assert workspace_from_points(np.zeros((0, 3)), "left").relative_area == 0.0
    flat = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.7, -0.7, 0.0], [np.nan, 0, 0]])
    ws = workspace_from_points(flat, "left")
    assert ws.relative_area == pytest.approx(0.0, abs=1e-6)
    assert ws.to_json()["quadrants"] == ws.quadrants


def test_ui_prmd_shoulder_abduction_covers_more_than_a_squat():
    raise_arm = reachable_workspace(read(UI_PRMD / "m07_s01_correct.bvh.gz"))
    squat = reachable_workspace(read(UI_PRMD / "m01_s01_correct.bvh.gz"))
    assert max(w.relative_area for w in raise_arm.values()) > 0.1
    assert max(w.relative_area for w in squat.values()) < 0.1


def _swept_right_arm() -> list[dict]:
    directions = cap(np.array([0.0, 0.0, 1.0]), 45.0, n_rings=6, n_around=40)
    rest = np.array([-1.0, 0.0, 0.0])
    return [
        {
            "RightUpperArm": _about(
                np.cross(rest, d), np.degrees(np.arccos(np.clip(rest @ d, -1, 1)))
            )
        }
        for d in directions
        if np.linalg.norm(np.cross(rest, d)) > 1e-9
    ]


def test_stored_workspace_only_for_exercises_of_the_arms():
    """The pipeline's workspace stage: per hand the areas and a small hull, for arm exercises."""
    from analysis.pipeline.clinical_stage import MAX_HULL_VERTICES, workspace_summaries
    from analysis.pipeline.results import AnalysisSummary

    motion = posed(_swept_right_arm())
    assert workspace_summaries(motion, ["KneeLeft", "HipLeft", "Spine"]) == {}  # a squat
    stored = workspace_summaries(motion, ["ShoulderRight", "ElbowRight"])
    full = reachable_workspace(motion)
    assert set(stored) == {"left", "right"}
    right = stored["right"]
    assert right.relative_area == pytest.approx(full["right"].relative_area, abs=1e-4)
    assert right.quadrants == pytest.approx(full["right"].quadrants, abs=1e-4)
    assert 4 <= len(right.vertices) <= MAX_HULL_VERTICES
    assert 3 * len(right.vertices) + 3 * len(right.faces) <= 400  # a few hundred numbers
    assert max(max(f) for f in right.faces) < len(right.vertices)
    summary = AnalysisSummary(1, 30.0, (), (), 0.0, workspace=stored)
    again = AnalysisSummary.from_json(summary.to_json())
    assert again.workspace == stored
    assert AnalysisSummary.from_json({}).workspace == {}  # runs stored before the field


@pytest.mark.parametrize("joints", [["LeftArm"], ["RightForeArm"], ["WristLeft"], ["RHand"]])
def test_arm_joints_of_any_rig_count_as_an_arm_exercise(joints):
    from analysis.clinical.labels import involves_arms

    assert involves_arms(joints)
    assert not involves_arms(["LeftUpLeg", "KneeRight", "Waist"])


def test_a_squat_that_moves_the_arms_is_not_an_arm_exercise():
    """The joints the UI-PRMD deep squat's tutor moves (m01) and the shoulder abduction's (m07)."""
    from analysis.clinical.labels import involves_arms

    squat = ["Head", "LeftCollar", "LeftUpperArm", "RightForearm", "LeftUpperLeg",
             "LeftLowerLeg", "LeftFoot", "RightUpperLeg", "RightLowerLeg", "RightFoot"]  # fmt: skip
    assert not involves_arms(squat)
    assert involves_arms(["RightCollar", "RightUpperArm", "RightForearm", "RightHand"])


def test_hull_and_area_from_trimesh_on_a_dense_cap():
    """The patch is trimesh's convex hull of the shoulder and the hand's directions, less the
    faces at the shoulder; its flat facets' area (trimesh) and its solid angle both give the
    cap's area within 5 %."""
    import trimesh

    points = cap(np.array([1.0, 0.0, 0.0]), 60.0, n_rings=24, n_around=180)
    ws = workspace_from_points(points, "right")
    hull = trimesh.convex.convex_hull(np.vstack((np.zeros((1, 3)), points)))
    at_shoulder = np.linalg.norm(hull.vertices, axis=1) < 1e-6
    away = ~at_shoulder[hull.faces].any(axis=1)
    patch = trimesh.Trimesh(hull.vertices, hull.faces[away], process=False)
    assert len(ws.faces) == int(away.sum())
    assert ws.relative_area == pytest.approx(cap_share(60.0), rel=0.01)
    assert patch.area / (2 * np.pi) == pytest.approx(cap_share(60.0), rel=0.05)
    assert patch.area / (2 * np.pi) < ws.relative_area  # chords lie inside the sphere
