"""Issue 26, angles a clinician would sign: no angle beyond what a body can reach on any recording
of the repository's test data, on any rig (a reading beyond the limits is left out or the angle
is "not measurable in this recording", with the reason); shoulder elevation equal to the angle
between upper arm and trunk from the joint positions on UI-PRMD shoulder abductions; standing
frames reading 0 ± 10° at hips, knees and shoulders on every rig; and a Bandai-Namco-style rig
(static root above the hips, six channels per joint, a rest pose lying along local +x: the
cause of the hip abduction of −80°/+81° while standing) reading the same as the original rig."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analysis.assessment.compensations import NOT_RELIABLE
from analysis.bvh import Motion, read
from analysis.clinical import ANGLE_NAMES, LIMITS, clinical_angles, limits_for, measure
from analysis.clinical.body import rest_positions
from analysis.clinical.labels import symmetry_rows
from analysis.clinical.measured import MAX_BEYOND_SHARE, NOT_MEASURABLE, within_limits
from analysis.kinematics import positions
from tests.analysis.bandai_style import bandai_style

ROOT = Path(__file__).resolve().parents[2]
UI_PRMD = ROOT / "data" / "ui-prmd"
RIGS = ROOT / "data" / "rigs"
RECORDINGS = sorted(
    [
        *UI_PRMD.glob("sessions/*.bvh.gz"),
        *UI_PRMD.glob("reps/*.bvh.gz"),
        *RIGS.glob("*.bvh"),
        *(ROOT / "tests").rglob("*.bvh"),
    ]
)


def test_the_test_data_is_there():
    assert len(RECORDINGS) > 200  # 140 sessions, 60 repetitions, 8 rigs, fixtures


@pytest.mark.parametrize("path", RECORDINGS, ids=[p.name.split(".")[0] for p in RECORDINGS])
def test_no_angle_beyond_the_body_limits_and_every_absent_angle_says_why(path):
    motion = read(path)
    measured = measure(motion)
    ranges = clinical_angles(motion)
    for name, angle in ranges.items():
        low, high = limits_for(name)
        assert low <= angle.min <= angle.max <= high, (name, angle)
    assert set(ranges) | set(measured.notes) == set(ANGLE_NAMES)
    assert not set(ranges) & set(measured.notes)
    assert all(note.startswith((NOT_MEASURABLE, NOT_RELIABLE)) for note in measured.notes.values())


BANDAI_STYLE = ["sessions/m01_s01_correct", "sessions/m07_s01_correct", "reps/m03_s01_e02"]


@pytest.mark.parametrize("name", BANDAI_STYLE)
def test_bandai_style_rig_stays_within_the_limits(name):
    ranges = clinical_angles(bandai_style(read(UI_PRMD / f"{name}.bvh.gz")))
    assert {"hip_flexion_left", "shoulder_elevation_right", "trunk_flexion"} <= set(ranges)
    for angle_name, angle in ranges.items():
        low, high = limits_for(angle_name)
        assert low <= angle.min <= angle.max <= high, (angle_name, angle)


def test_readings_beyond_the_limits_are_left_out_or_make_the_angle_not_measurable():
    frames = 100
    knee = np.full(frames, 40.0)
    knee[:3] = 175.0  # a glitch: 3 % of the frames
    ankle = np.full(frames, -20.0)
    ankle[:20] = -89.0  # a lost foot: 20 % of the frames
    lost = np.full(frames, np.nan)
    measured = within_limits(
        {"knee_flexion_left": knee, "ankle_dorsiflexion_right": ankle, "elbow_flexion_left": lost}
    )
    assert MAX_BEYOND_SHARE * frames >= 3
    assert np.isnan(measured.series["knee_flexion_left"][:3]).all()
    assert np.nanmax(measured.series["knee_flexion_left"]) == 40.0
    assert set(measured.series) == {"knee_flexion_left"}
    note = measured.notes["ankle_dorsiflexion_right"]
    assert note.startswith("not measurable in this recording: 20 % of the frames")
    assert "−60° to 45°" in note and "up to −89°" in note and "_" not in note
    assert measured.notes["elbow_flexion_left"].endswith("not tracked in any frame")


def test_limits_are_wider_than_the_normal_ranges_and_cover_every_angle():
    from analysis.clinical import norm_for

    assert set(LIMITS) == {norm_for(n).angle for n in ANGLE_NAMES}
    for name in ANGLE_NAMES:
        norm, (low, high) = norm_for(name), limits_for(name)
        assert low <= norm.minimum and norm.maximum <= high
    assert limits_for("knee_flexion_left") == (-15.0, 165.0)
    assert limits_for("shoulder_elevation_right") == (0.0, 185.0)


def test_a_skeleton_without_legs_says_which_segments_are_missing():
    from tests.synthetic_motion import skeleton  # no feet, no collars, legs end at the knee

    sk = skeleton()
    notes = measure(Motion(sk, np.zeros((3, sk.n_channels)), 1 / 30)).notes
    assert (
        notes["knee_flexion_left"] == f"{NOT_MEASURABLE}: the capture does not track the lower leg"
    )
    assert "foot" in notes["ankle_dorsiflexion_right"]
    assert "elbow_flexion_left" not in notes


# --- shoulder elevation against the joint positions --------------------------------------------

ABDUCTIONS = sorted(UI_PRMD.glob("sessions/m07_*.bvh.gz"))


def arm_to_trunk(motion: Motion, side: str) -> np.ndarray:
    """Per frame, the angle (degrees) between the upper arm (shoulder → elbow) and the trunk's
    downward line (neck → waist), from the joint positions alone."""
    at = {n: i for i, n in enumerate(motion.skeleton.names)}
    pos = positions(motion)
    arm = pos[:, at[f"{side.capitalize()}Forearm"]] - pos[:, at[f"{side.capitalize()}UpperArm"]]
    down = pos[:, at["Waist"]] - pos[:, at["Neck"]]
    cos = np.sum(arm * down, -1) / np.linalg.norm(arm, axis=-1) / np.linalg.norm(down, axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def test_the_repository_holds_the_ui_prmd_shoulder_abductions():
    assert len(ABDUCTIONS) == 14


@pytest.mark.parametrize("path", ABDUCTIONS, ids=[p.name.split(".")[0] for p in ABDUCTIONS])
def test_shoulder_elevation_is_the_arm_to_trunk_angle_within_5_degrees(path):
    motion = read(path)
    series = measure(motion).series
    raised = []
    for side in ("left", "right"):
        truth = arm_to_trunk(motion, side)
        elevation = series[f"shoulder_elevation_{side}"]
        assert np.isfinite(elevation).all()
        assert np.abs(elevation - truth).max() < 5.0  # every frame
        raised.append((truth.max(), side))
    top, side = max(raised)
    assert top > 120  # one arm is raised well above the shoulder
    # and a goniometer's abduction reads that elevation, not a share of it (issue 26: "130°" for
    # an arm 164° from the trunk)
    abduction = clinical_angles(motion)[f"shoulder_abduction_{side}"]
    assert abs(abduction.max - top) < 5.0


# --- standing frames --------------------------------------------------------------------------
# Per rig, a frame where the person stands (first frame of most files) and the parts held in
# their neutral position there; a part the recording holds elsewhere in every frame close to
# standing is listed with the reason, and the positions must confirm it (more than 10° from
# neutral), so an exception cannot hide a wrong zero.
PARTS = ("hip", "knee", "shoulder", "ankle")
STANDING = {
    "ui-prmd m07_s01_correct": (UI_PRMD / "sessions/m07_s01_correct.bvh.gz", 0, {}),
    # the demo's shoulder abduction (webapp/demo/clinic.py): the patient stands still throughout
    # (feet set apart: the thighs 12–14° from the trunk line; the arms held 13–14° out)
    "demo m07_s02_correct": (UI_PRMD / "sessions/m07_s02_correct.bvh.gz", 0, {
        "hip_left": "feet set apart", "hip_right": "feet set apart",
        "shoulder_left": "arms held a little out", "shoulder_right": "arms held a little out",
    }),
    "ui-prmd m01_s01_correct": (UI_PRMD / "sessions/m01_s01_correct.bvh.gz", 0, {
        "hip_left": "feet set wide for the squat", "hip_right": "feet set wide for the squat",
        "shoulder_left": "the squatters hold both arms up in a V throughout",
        "shoulder_right": "the squatters hold both arms up in a V throughout",
    }),
    # FAIR capture, Z-up: standing between waves; the right arm is waving in the stillest frames
    "fair1_wave_hello": (RIGS / "AnimatedDrawings_fair1_wave_hello.bvh", 420, {
        "shoulder_right": "waving",
    }),
    # CMU 01_01 (cgspeed): frame 0 is the T-pose; after it the knees never straighten below 20°
    "assimp_01_01": (RIGS / "assimp_01_01.bvh", 937, {
        "knee_left": "knees bent in every frame after the T-pose",
        "knee_right": "knees bent in every frame after the T-pose",
        "ankle_left": "knees bent over the feet", "ankle_right": "knees bent over the feet",
    }),
    # jumping jacks: the knees stay bent 24° or more throughout; arms down at the start
    "cmu1_jumping_jacks": (RIGS / "AnimatedDrawings_cmu1_jumping_jacks.bvh", 45, {
        "knee_left": "jumping", "knee_right": "jumping", "hip_left": "jumping",
        "hip_right": "jumping", "ankle_left": "jumping", "ankle_right": "jumping",
    }),
    # a walk: no frame with both legs straight; the left leg in mid-stance
    "PyMO_walk": (RIGS / "PyMO_AV_8Walk_Meredith_HVHA_Rep1.bvh", 5, {
        "knee_right": "swinging leg", "hip_right": "swinging leg",
        "shoulder_right": "swinging arm", "ankle_left": "the body rolls over the standing foot",
    }),
    # a dance: knees bent and arms held out at the start, hips straight
    "rokoko_dance": (RIGS / "AnimatedDrawings_rokoko_jesse_dance.bvh", 0, {
        "knee_left": "dancing", "knee_right": "dancing", "shoulder_left": "arms held out",
        "shoulder_right": "arms held out", "ankle_left": "dancing", "ankle_right": "dancing",
    }),
    # CMU 131_01 (3dsMax conversion): a stretch, the right leg and both arms near neutral
    "bvh11_131_01": (RIGS / "bvh11_131_01.bvh", 570, {
        "knee_left": "lunging", "knee_right": "lunging", "hip_left": "lunging",
        "ankle_right": "lunging",
    }),
    # MakeHuman, 14 frames of a walk: arms down, legs striding
    "makehuman_walk1": (RIGS / "makehuman_walk1.bvh", 0, {
        "knee_left": "striding", "knee_right": "striding", "hip_left": "striding",
        "hip_right": "striding", "ankle_left": "striding", "ankle_right": "striding",
    }),
}  # fmt: skip
READINGS = {
    "hip": ("hip_flexion", "hip_abduction"),
    "knee": ("knee_flexion",),
    "shoulder": ("shoulder_elevation", "shoulder_flexion", "shoulder_abduction"),
    "ankle": ("ankle_dorsiflexion",),
}


def _angle(u: np.ndarray, v: np.ndarray) -> float:
    return float(
        np.degrees(np.arccos(np.clip(u @ v / np.linalg.norm(u) / np.linalg.norm(v), -1, 1)))
    )


def from_positions(motion: Motion, frame: int) -> dict[str, float]:
    """Per part and side, its angle from neutral from the joint positions alone: the knee's
    bend, the thigh's and the upper arm's angle to the trunk line (hips' midpoint → neck)."""
    from analysis.clinical.body import find_body, find_joints, geometry, take_vertical

    j, pos = find_joints(motion.skeleton), positions(motion)[frame]
    up = geometry(motion, "positions").up if find_body(motion.skeleton).upright else None
    if up is None:  # a rest pose lying down: the take's vertical
        up = take_vertical(positions(motion), find_body(motion.skeleton))
    trunk = pos[j.get("neck", j.get("chest"))] - (pos[j["hip_left"]] + pos[j["hip_right"]]) / 2
    out = {}
    for s in ("left", "right"):
        hip, knee, ankle = pos[j[f"hip_{s}"]], pos[j[f"knee_{s}"]], pos[j[f"ankle_{s}"]]
        out[f"knee_{s}"] = _angle(knee - hip, ankle - knee)
        out[f"hip_{s}"] = _angle(knee - hip, -trunk)
        out[f"shoulder_{s}"] = _angle(pos[j[f"elbow_{s}"]] - pos[j[f"shoulder_{s}"]], -trunk)
        # the ankle's bend from standing on a flat foot: the shank's lean from the vertical
        # towards the toes (no rig has a heel, so a flat foot is what this truth assumes)
        toes = pos[j[f"toe_{s}"]] - ankle
        toes -= (toes @ up) * up
        out[f"ankle_{s}"] = 90.0 - _angle(knee - ankle, toes)
    return out


@pytest.mark.parametrize("rig", list(STANDING))
def test_a_standing_frame_reads_near_zero_at_hips_knees_and_shoulders(rig):
    path, frame, elsewhere = STANDING[rig]
    motion = read(path)
    series = measure(motion).series
    truth = from_positions(motion, frame)
    for part in PARTS:
        for side in ("left", "right"):
            key = f"{part}_{side}"
            if key in elsewhere:  # the person holds this part away from neutral here
                assert abs(truth[key]) > 10.0, (key, elsewhere[key], truth[key])
                continue
            if part == "ankle" and f"ankle_dorsiflexion_{side}" not in series:
                # a foot the capture cannot give a neutral for says why instead of a number
                assert measure(motion).notes[f"ankle_dorsiflexion_{side}"]
                continue
            values = {n: float(series[f"{n}_{side}"][frame]) for n in READINGS[part]}
            assert all(abs(v) <= 10.0 for v in values.values()), (key, values)
    assert len(elsewhere) < 2 * len(PARTS) - 1  # something stands in every file


def test_the_bandai_style_standing_frame_reads_near_zero():
    motion = bandai_style(read(UI_PRMD / "sessions/m07_s01_correct.bvh.gz"))
    series = measure(motion).series
    for part in PARTS:
        for side in ("left", "right"):
            for name in READINGS[part]:
                assert abs(series[f"{name}_{side}"][0]) <= 10.0, (name, side)


# --- the Bandai-Namco-style rig -----------------------------------------------------------------


def test_rest_pose_keeps_each_joints_offset_where_joints_have_position_channels():
    original = read(UI_PRMD / "sessions/m07_s01_correct.bvh.gz")
    rig = bandai_style(original).skeleton
    rest = rest_positions(rig)
    # every joint at its offset from its parent (all-zero channels would put it at the origin)
    for j, parent in enumerate(rig.parents):
        expected = rig.offsets[j] + (rest[parent] if parent >= 0 else 0.0)
        assert np.allclose(rest[j], expected)
    assert np.ptp(rest, axis=0).max() > 50.0  # the figure has a size: it lies along +x


@pytest.mark.parametrize("name", ["m07_s01_correct", "m01_s01_correct", "m10_s02_correct"])
def test_bandai_style_rig_reads_the_angles_of_the_original(name):
    original = read(UI_PRMD / f"sessions/{name}.bvh.gz")
    same = bandai_style(original)
    assert np.allclose(positions(same)[:, 1:], positions(original), atol=1e-6)
    before = measure(original)
    after = measure(same)
    shared = set(before.series) & set(after.series)
    assert shared >= {
        n
        for n in ANGLE_NAMES
        if not n.startswith(("ankle", "shoulder_rotation")) and not n.startswith("shoulder_plane")
    }  # defined where the arm is up
    # the ankles too: their zero comes from the person standing, not from the rest pose (which
    # lies along +x here)
    assert set(before.series) == set(after.series) == shared
    if name == "m07_s01_correct":  # standing still: both feet steady enough to measure
        assert {"ankle_dorsiflexion_left", "ankle_dorsiflexion_right"} <= shared
    worst = {
        n: float(np.nanmax(np.abs(before.series[n] - after.series[n]))) for n in sorted(shared)
    }
    assert max(worst.values()) < 2.0, worst


# --- the ankle's zero from the person standing (issue 35 item 3) --------------------------------


def test_the_demo_shoulder_abduction_reads_its_still_ankles_near_zero():
    # the patient stands still: the rig's rest pose read these ankles at −44° to −31°
    series = measure(read(UI_PRMD / "sessions/m07_s02_correct.bvh.gz")).series
    for side in ("left", "right"):
        ankle = series[f"ankle_dorsiflexion_{side}"]
        assert np.nanpercentile(np.abs(ankle), 95) <= 10.0, side


@pytest.mark.parametrize("name", ["m05_s03_correct", "m05_s03_incorrect"])
def test_the_demo_sit_to_stand_reports_no_ankle_asymmetry_from_a_jumping_foot(name):
    motion = read(UI_PRMD / f"sessions/{name}.bvh.gz")
    measured = measure(motion)
    rows = {r["label"]: r for r in symmetry_rows(clinical_angles(motion))}
    ankle = rows.get("Ankle dorsiflexion")
    # an ankle shown on both sides differs by what the feet did, not by 43° of noise; a foot
    # the capture loses between frames is named instead
    assert ankle is None or abs(ankle["difference"]) <= 15.0, ankle
    if ankle is None:
        lost = [n for n in measured.notes if n.startswith("ankle")]
        assert lost and all(
            measured.notes[n].startswith((NOT_RELIABLE, NOT_MEASURABLE)) for n in lost
        )


def test_a_foot_jumping_between_frames_is_not_measurable_reliably():
    frames = 200
    steady = 10.0 * np.sin(np.linspace(0, 6 * np.pi, frames))
    jumping = steady + np.where(np.arange(frames) % 2 == 0, 20.0, -20.0)
    measured = within_limits(
        {"ankle_dorsiflexion_left": steady, "ankle_dorsiflexion_right": jumping}
    )
    assert set(measured.series) == {"ankle_dorsiflexion_left"}
    note = measured.notes["ankle_dorsiflexion_right"]
    assert note.startswith(NOT_RELIABLE) and "from one frame to the next" in note


def test_frames_where_the_capture_lost_a_shoulder_are_left_out_of_that_shoulders_angles_only():
    motion = read(ABDUCTIONS[0])
    lost = np.zeros(motion.n_frames, dtype=bool)
    lost[20:40] = True
    plain = measure(motion).series
    marked = measure(motion, lost={"left_shoulder": lost}).series
    blanked = [n for n in plain if n.startswith("shoulder_") and n.endswith("_left")]
    assert {"shoulder_elevation_left", "shoulder_flexion_left"} <= set(blanked)
    assert set(marked) == set(plain)
    for name in plain:
        if name in blanked:
            assert np.isnan(marked[name][lost]).all()
            np.testing.assert_array_equal(marked[name][~lost], plain[name][~lost])
        else:  # the elbow, the other shoulder, the trunk: as measured
            np.testing.assert_array_equal(marked[name], plain[name])
