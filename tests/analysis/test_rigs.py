"""Other capture systems onto an exercise's skeleton: body parts found by names and structure,
recordings retargeted by segment rotations (`analysis.kinematics.map_onto`).

The UI-PRMD deep squat is re-exported under a CMU-style and a Mixamo-style skeleton (other names,
extra spine and neck joints, hip joints of zero length, Z-up, A-pose arms, other rest bone
directions and channel orders, other units) by an independent builder below; mapped back, its
world bone directions must match the original's. The real rigs of `data/rigs/` must all map.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import Motion, Skeleton, SkeletonMismatchError, dumps, read
from analysis.bvh.rigs import identify
from analysis.kinematics import map_onto, positions
from analysis.kinematics import quaternions as quat
from analysis.kinematics.forward_kinematics import world

ROOT = Path(__file__).resolve().parents[2]
UI_PRMD = ROOT / "data" / "ui-prmd"
RIGS = ROOT / "data" / "rigs"
TUTOR = UI_PRMD / "sessions" / "m01_s01_correct.bvh.gz"
SESSION = UI_PRMD / "sessions" / "m01_s02_correct.bvh.gz"


@pytest.fixture(scope="module")
def tutor() -> Motion:
    return read(TUTOR)


@pytest.fixture(scope="module")
def session() -> Motion:
    return read(SESSION)


# ------------------------------------------------------------------ an independent re-exporter

# A point of the original: a joint name, or (a, b, t): the point at t along a → b.
Point = str | tuple[str, str, float]


@dataclass(frozen=True)
class NewJoint:
    name: str
    parent: str | None
    point: Point
    # Rest direction of the bone from the parent, in the original's (y-up) frame; None: the
    # original's rest direction between the two points (needed where a joint has several bones).
    rest: tuple[float, float, float] | None = None


def _rot_x(degrees: float) -> np.ndarray:
    a = np.radians(degrees)
    return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])


def _rot_z(degrees: float) -> np.ndarray:
    a = np.radians(degrees)
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])


def _min_rot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rodrigues: the smallest rotation taking direction a onto b (not antiparallel)."""
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    v, c = np.cross(a, b), np.sum(a * b, axis=-1)
    k = np.zeros((*v.shape[:-1], 3, 3))
    k[..., 0, 1], k[..., 0, 2], k[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    k = k - np.swapaxes(k, -1, -2)
    return np.eye(3) + k + k @ k / (1 + c)[..., None, None]


def _kabsch(u: np.ndarray, d: np.ndarray) -> np.ndarray:
    h = np.einsum("ki,fkj->fij", u, d)
    a, _, bt = np.linalg.svd(h)
    s = np.sign(np.linalg.det(np.swapaxes(bt, 1, 2) @ np.swapaxes(a, 1, 2)))
    fix = np.stack([np.ones_like(s), np.ones_like(s), s], axis=-1)
    return (np.swapaxes(bt, 1, 2) * fix[:, None, :]) @ np.swapaxes(a, 1, 2)


def reexport(  # noqa: C901 (a test builder kept in one piece to read against the docstring)
    motion: Motion,
    joints: list[NewJoint],
    channels: str,
    *,
    turn: np.ndarray,
    unit: float,
    end_sites: dict[str, Point],
) -> Motion:
    """The motion written by another rig: every new joint sits exactly on its point of the
    original (``turn`` applied to the world, lengths × ``unit``)."""
    sk = motion.skeleton
    pos = positions(motion)
    glob = quat.to_matrix(world(motion)[0])
    rest_pos = positions(motion.with_frames(np.zeros((1, sk.n_channels))))[0]

    def where(point: Point, p: np.ndarray) -> np.ndarray:
        if isinstance(point, str):
            return p[..., sk.index(point), :]
        a, b, t = point
        return (1 - t) * p[..., sk.index(a), :] + t * p[..., sk.index(b), :]

    def nearest_original(point: Point) -> int:
        return sk.index(point if isinstance(point, str) else point[0])

    names = [j.name for j in joints]
    parents = [names.index(j.parent) if j.parent else -1 for j in joints]
    world_pts = np.stack([where(j.point, pos) for j in joints], axis=1) @ turn.T * unit
    rest_pts = np.stack([where(j.point, rest_pos) for j in joints]) @ turn.T * unit
    offsets = np.zeros((len(joints), 3))
    for k, j in enumerate(joints):
        if parents[k] < 0:
            continue
        actual = rest_pts[k] - rest_pts[parents[k]]
        length = np.linalg.norm(actual)
        direction = actual if j.rest is None else turn @ np.array(j.rest)
        offsets[k] = direction / max(np.linalg.norm(direction), 1e-12) * length
    end_names = list(end_sites)
    end_parents = [names.index(n) for n in end_names]
    end_pts = [where(end_sites[n], pos) @ turn.T * unit for n in end_names]
    end_offsets = np.array(
        [
            turn
            @ (where(end_sites[n], rest_pos) - where(joints[names.index(n)].point, rest_pos))
            * unit
            for n in end_names
        ]
    ).reshape(-1, 3)
    n_frames = pos.shape[0]
    new_glob = np.zeros((n_frames, len(joints), 3, 3))
    for k, j in enumerate(joints):
        kids = [c for c in range(len(joints)) if parents[c] == k and np.linalg.norm(offsets[c]) > 0]
        vec_u = [offsets[c] for c in kids]
        vec_rest = [rest_pts[c] - rest_pts[k] for c in kids]
        vec_d = [world_pts[:, c] - world_pts[:, k] for c in kids]
        if j.name in end_sites:
            e = end_names.index(j.name)
            if np.linalg.norm(end_offsets[e]) > 0:
                vec_u.append(end_offsets[e])
                vec_rest.append(end_offsets[e])
                vec_d.append(end_pts[e] - world_pts[:, k])
        twist = turn @ glob[:, nearest_original(j.point)] @ turn.T
        if len(vec_u) >= 2:
            new_glob[:, k] = _kabsch(np.array(vec_u), np.stack(vec_d, axis=1))
        elif len(vec_u) == 1:
            guess = twist @ _min_rot(vec_u[0], vec_rest[0])
            new_glob[:, k] = _min_rot(np.einsum("fij,j->fi", guess, vec_u[0]), vec_d[0]) @ guess
        else:
            new_glob[:, k] = twist
    frames = []
    for k in range(len(joints)):
        local = new_glob[:, k]
        if parents[k] >= 0:
            local = np.swapaxes(new_glob[:, parents[k]], 1, 2) @ local
        angles = quat.matrix_to_euler(local, channels)
        if parents[k] < 0:
            frames.append(world_pts[:, k])
        frames.append(angles)
    skeleton = Skeleton(
        names=tuple(names),
        parents=np.array(parents, dtype=np.int64),
        offsets=offsets,
        channels=tuple(
            (("Xposition", "Yposition", "Zposition") if p < 0 else ())
            + tuple(f"{a}rotation" for a in channels)
            for p in parents
        ),
        end_site_parents=np.array(end_parents, dtype=np.int64),
        end_site_offsets=end_offsets,
    )
    return Motion(skeleton, np.concatenate(frames, axis=1), motion.frame_time)


DOWN, UP, FORWARD = (0.0, -1.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
A_LEFT, A_RIGHT = (0.7, -0.7, 0.0), (-0.7, -0.7, 0.0)


def _limbs(side: str, arm_rest, names: dict[str, str], collar: str) -> list[NewJoint]:
    s = side
    return [
        NewJoint(names["collar"], collar, f"{s}Collar"),
        NewJoint(names["arm"], names["collar"], f"{s}UpperArm"),
        NewJoint(names["forearm"], names["arm"], f"{s}Forearm", arm_rest),
        NewJoint(names["hand"], names["forearm"], f"{s}Hand", arm_rest),
    ]


def cmu_style(motion: Motion) -> Motion:
    """CMU/cgspeed-like: zero-length hip joints, LowerBack-Spine-Spine1 spine, Neck + Neck1,
    collars named Shoulder, ZYX channels, inches, arms in a T with straight-down legs."""
    joints = [NewJoint("Hips", None, "Waist")]
    for side, s in (("Left", "L"), ("Right", "R")):
        joints += [
            NewJoint(f"{s}HipJoint", "Hips", "Waist", (1.0, 0.0, 0.0)),
            NewJoint(f"{side}UpLeg", f"{s}HipJoint", f"{side}UpperLeg"),
            NewJoint(f"{side}Leg", f"{side}UpLeg", f"{side}LowerLeg", DOWN),
            NewJoint(f"{side}Foot", f"{side}Leg", f"{side}Foot", DOWN),
            NewJoint(f"{side}ToeBase", f"{side}Foot", f"{side}Toes", FORWARD),
        ]
    joints += [
        NewJoint("LowerBack", "Hips", ("Waist", "Spine", 0.4)),
        NewJoint("Spine", "LowerBack", "Spine", UP),
        NewJoint("Spine1", "Spine", "Chest", UP),
        NewJoint("Neck", "Spine1", "Neck"),
        NewJoint("Neck1", "Neck", ("Neck", "Head", 0.5), UP),
        NewJoint("Head", "Neck1", "Head", UP),
    ]
    for side in ("Left", "Right"):
        sign = 1.0 if side == "Left" else -1.0
        joints += [
            NewJoint(f"{side}Shoulder", "Spine1", f"{side}Collar"),
            NewJoint(f"{side}Arm", f"{side}Shoulder", f"{side}UpperArm", (sign, 0.0, 0.0)),
            NewJoint(f"{side}ForeArm", f"{side}Arm", f"{side}Forearm", (sign, 0.0, 0.0)),
            NewJoint(f"{side}Hand", f"{side}ForeArm", f"{side}Hand", (sign, 0.0, 0.0)),
        ]
    return reexport(
        motion,
        joints,
        "ZYX",
        turn=np.eye(3),
        unit=1 / 2.54,
        end_sites={"Head": "HeadTip", "LeftToeBase": "LeftToes", "RightToeBase": "RightToes"},
    )


def mixamo_style(motion: Motion) -> Motion:
    """Mixamo-like (as exported Z-up from Blender): ``mixamorig:`` names, Spine-Spine1-Spine2,
    HeadTop_End joint, A-pose arms, XYZ channels, metres."""
    m = "mixamorig:"
    joints = [
        NewJoint(f"{m}Hips", None, "Waist"),
        NewJoint(f"{m}Spine", f"{m}Hips", "Spine"),
        NewJoint(f"{m}Spine1", f"{m}Spine", ("Spine", "Chest", 0.5), UP),
        NewJoint(f"{m}Spine2", f"{m}Spine1", "Chest", UP),
        NewJoint(f"{m}Neck", f"{m}Spine2", "Neck"),
        NewJoint(f"{m}Head", f"{m}Neck", "Head", UP),
        NewJoint(f"{m}HeadTop_End", f"{m}Head", "HeadTip", UP),
    ]
    for side in ("Left", "Right"):
        rest = A_LEFT if side == "Left" else A_RIGHT
        joints += [
            NewJoint(f"{m}{side}Shoulder", f"{m}Spine2", f"{side}Collar"),
            NewJoint(f"{m}{side}Arm", f"{m}{side}Shoulder", f"{side}UpperArm", rest),
            NewJoint(f"{m}{side}ForeArm", f"{m}{side}Arm", f"{side}Forearm", rest),
            NewJoint(f"{m}{side}Hand", f"{m}{side}ForeArm", f"{side}Hand", rest),
            NewJoint(f"{m}{side}UpLeg", f"{m}Hips", f"{side}UpperLeg"),
            NewJoint(f"{m}{side}Leg", f"{m}{side}UpLeg", f"{side}LowerLeg", (0.0, -1.0, 0.1)),
            NewJoint(f"{m}{side}Foot", f"{m}{side}Leg", f"{side}Foot", (0.0, -1.0, -0.1)),
            NewJoint(f"{m}{side}ToeBase", f"{m}{side}Foot", f"{side}Toes", (0.0, -0.5, 1.0)),
        ]
    return reexport(
        motion,
        joints,
        "XYZ",
        turn=_rot_x(90) @ _rot_z(0),
        unit=0.01,
        end_sites={},
    )


BONES = [
    ("Waist", "Chest"), ("Chest", "Head"), ("Head", "HeadTip"),
    ("LeftUpperArm", "LeftForearm"), ("LeftForearm", "LeftHand"),
    ("RightUpperArm", "RightForearm"), ("RightForearm", "RightHand"),
    ("LeftUpperLeg", "LeftLowerLeg"), ("LeftLowerLeg", "LeftFoot"), ("LeftFoot", "LeftToes"),
    ("RightUpperLeg", "RightLowerLeg"), ("RightLowerLeg", "RightFoot"),
    ("RightFoot", "RightToes"), ("LeftCollar", "LeftUpperArm"), ("Waist", "LeftUpperLeg"),
]  # fmt: skip


def bone_angles(a: Motion, b: Motion) -> dict[str, float]:
    """Per bone, the 99th percentile over frames of the angle (degrees) between a's and b's."""
    pa, pb = positions(a), positions(b)
    out = {}
    for top, end in BONES:
        i, j = a.skeleton.index(top), a.skeleton.index(end)
        k, m = b.skeleton.index(top), b.skeleton.index(end)
        va, vb = pa[:, j] - pa[:, i], pb[:, m] - pb[:, k]
        cos = np.sum(va * vb, axis=1) / np.linalg.norm(va, axis=1) / np.linalg.norm(vb, axis=1)
        out[f"{top}-{end}"] = float(np.percentile(np.degrees(np.arccos(np.clip(cos, -1, 1))), 99))
    return out


@pytest.mark.parametrize("style", [cmu_style, mixamo_style], ids=["cmu", "mixamo"])
def test_a_reexported_session_maps_back_onto_the_ui_prmd_skeleton(style, tutor, session):
    other = read(dumps(style(session)))
    assert set(other.skeleton.names).isdisjoint(tutor.skeleton.names) or style is cmu_style
    # The re-export really is the same movement (the builder is exact up to 6 decimals).
    mapped = map_onto(other, tutor.skeleton)
    assert mapped.skeleton.names == tutor.skeleton.names
    assert mapped.skeleton.channels == tutor.skeleton.channels
    assert mapped.n_frames == session.n_frames and mapped.frame_time == session.frame_time
    worst = bone_angles(session, mapped)
    assert max(worst.values()) < 3.0, worst


def test_reexported_sessions_score_like_the_original(tutor):
    from analysis.pipeline import analyse, build_model
    from tests.analysis.test_pipeline import landmarks

    model = build_model(tutor, *landmarks("sessions/m01_s01_correct.bvh.gz"))
    session = read(SESSION)
    score = analyse(session, model).to_json()["score"]
    for style in (cmu_style, mixamo_style):
        mapped = map_onto(read(dumps(style(session))), tutor.skeleton)
        assert analyse(mapped, model).to_json()["score"] == pytest.approx(score, abs=2.0)


# ------------------------------------------------------------------ real files of other rigs

MAPPABLE = [
    "AnimatedDrawings_cmu1_jumping_jacks.bvh",
    "AnimatedDrawings_fair1_wave_hello.bvh",
    "AnimatedDrawings_rokoko_jesse_dance.bvh",
    "PyMO_AV_8Walk_Meredith_HVHA_Rep1.bvh",
    "assimp_01_01.bvh",
    "bvh11_131_01.bvh",
    "makehuman_walk1.bvh",
]


Z_UP = {"AnimatedDrawings_fair1_wave_hello.bvh", "makehuman_walk1.bvh"}


def test_the_rig_folder_holds_the_eight_files():
    assert sorted(p.name for p in RIGS.glob("*.bvh")) == sorted(
        [*MAPPABLE, "fairmotion_sinusoidal.bvh"]
    )


@pytest.mark.parametrize("name", MAPPABLE)
def test_each_real_rig_maps_onto_the_ui_prmd_skeleton(name, tutor):
    motion = read(RIGS / name)
    mapped = map_onto(motion, tutor.skeleton)
    sk = mapped.skeleton
    assert sk.names == tutor.skeleton.names and sk.channels == tutor.skeleton.channels
    assert mapped.n_frames == motion.n_frames and np.isfinite(mapped.frames).all()
    p = positions(mapped)
    # Upright in the exercise's y-up world (Z-up files turned), head above hips above feet,
    # left on the left: the subject's left hand is on the +x side when facing +z.
    head, waist = p[:, sk.index("HeadTip")], p[:, sk.index("Waist")]
    feet = 0.5 * (p[:, sk.index("LeftFoot")] + p[:, sk.index("RightFoot")])
    assert np.median(head[:, 1] - waist[:, 1]) > 30 and np.median(waist[:, 1] - feet[:, 1]) > 30
    # Bone directions: the retargeted thigh and shin point where the recording's do.
    source = positions(motion)
    roles = identify(motion.skeleton)
    turn = _rot_x(-90) if name in Z_UP else np.eye(3)
    for side in ("left", "right"):
        for top, end, a, b in (
            ("upper_leg", "lower_leg", "UpperLeg", "LowerLeg"),
            ("upper_arm", "forearm", "UpperArm", "Forearm"),
        ):
            cap = side.capitalize()
            want = (source[:, roles[f"{side}_{end}"]] - source[:, roles[f"{side}_{top}"]]) @ turn.T
            got = p[:, sk.index(cap + b)] - p[:, sk.index(cap + a)]
            cos = np.sum(want * got, 1) / np.linalg.norm(want, axis=1) / np.linalg.norm(got, axis=1)
            assert np.degrees(np.arccos(np.clip(cos, -1, 1))).max() < 1.0, (name, side, top)


def test_a_chain_without_a_body_is_refused_in_plain_words(tutor):
    with pytest.raises(SkeletonMismatchError) as caught:
        map_onto(read(RIGS / "fairmotion_sinusoidal.bvh"), tutor.skeleton)
    message = str(caught.value)
    assert "left upper arm" in message and "hips" in message and "head" in message
    assert "record a reference" in message
    for joint in ("base", "child1", "Waist", "LeftForearm"):
        assert joint not in message


def test_prepare_given_the_model_skeleton_retargets_another_rig(tutor, session):
    from analysis.pipeline.prepare import prepare

    other = read(dumps(mixamo_style(session.with_frames(session.frames[:90]))))
    prepared = prepare(other, tutor.skeleton, tutor.fps, rep_frames=60)
    assert prepared.motion.skeleton.names == tutor.skeleton.names
    assert prepared.points.shape == (90, len(tutor.skeleton.names), 3)
    same = prepare(session.with_frames(session.frames[:90]), tutor.skeleton, tutor.fps, 60)
    np.testing.assert_allclose(prepared.points, same.points, atol=0.02)
    with pytest.raises(SkeletonMismatchError, match="left upper arm"):
        prepare(read(RIGS / "fairmotion_sinusoidal.bvh"), tutor.skeleton, tutor.fps, 60)


def test_a_limb_part_out_of_order_below_a_dropped_one_is_checked_against_the_one_above():
    """Issue 25 (a hostile file): the forearm above the upper arm is dropped, and the hand below
    is then compared with the upper arm instead of ending in a KeyError."""
    lines = [
        "HIERARCHY",
        "ROOT Hips",
        "{",
        "OFFSET 0 0 0",
        "CHANNELS 3 Zrotation Xrotation Yrotation",
    ]
    chain = ["LeftForeArm", "LeftArm", "LeftHand"]
    for name in chain:
        lines += [f"JOINT {name}", "{", "OFFSET 1 0 0", "CHANNELS 3 Zrotation Xrotation Yrotation"]
    lines += ["End Site", "{", "OFFSET 1 0 0", "}"] + ["}"] * (len(chain) + 1)
    lines += ["MOTION", "Frames: 1", "Frame Time: 0.033333", " ".join(["0"] * 12)]
    roles = identify(read("\n".join(lines) + "\n").skeleton)
    assert "left_forearm" not in roles
    assert roles.get("left_hand") == 3 and roles.get("left_upper_arm") == 2
