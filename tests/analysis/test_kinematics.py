"""Forward kinematics against a second, independent implementation built on scipy's Rotation,
on every UI-PRMD file and on random skeletons with any channel layout."""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from analysis.bvh import Motion, read
from analysis.kinematics import forward_kinematics as kin
from tests.analysis import bvh_cases as bc

UI_PRMD = sorted(Path("data/ui-prmd").glob("*/*.bvh.gz"))
TOL = 1e-6


class ReferenceFK:
    """Scipy forward kinematics written from the BVH conventions, independent of analysis/.

    Rotation channels are intrinsic, applied in the declared order (uppercase scipy axes); position
    channels replace the OFFSET component on their axis. Global rotation = parent global · local;
    position = parent position + parent global rotation applied to the translation; the chain is
    composed with rotation matrices. ``full_euler`` builds each joint's local rotation with one
    ``Rotation.from_euler(axes, ...)``; otherwise (scipy's Euler code is slow, ~3 µs a rotation)
    with single-axis ``from_euler`` matrices multiplied in the declared order, which
    `test_reference_modes_agree` ties to the full-Euler mode.
    """

    def __init__(self, parents, offsets, channels, frames, full_euler=True):
        n_frames, n_joints = frames.shape[0], len(parents)
        self.translation = np.tile(np.asarray(offsets, dtype=float), (n_frames, 1, 1))
        self.local = np.tile(np.eye(3), (n_frames, n_joints, 1, 1))
        rotation_columns = self._split_channels(channels, frames)
        if full_euler:
            self._full_euler(rotation_columns, frames)
        else:
            self._by_axis(rotation_columns, frames)
        self.glob = self.local.copy()
        self.pos = self.translation.copy()
        for j, parent in enumerate(parents):
            if parent >= 0:
                self.glob[:, j] = self.glob[:, parent] @ self.local[:, j]
                self.pos[:, j] = self.pos[:, parent] + np.einsum(
                    "fab,fb->fa", self.glob[:, parent], self.translation[:, j]
                )

    def _split_channels(self, channels, frames):
        """Position channels go into the translations; returns [(joint, axes, columns)]."""
        out, start = [], 0
        for j, names in enumerate(channels):
            axes, columns = "", []
            for k, name in enumerate(names):
                if name.endswith("position"):
                    self.translation[:, j, "XYZ".index(name[0])] = frames[:, start + k]
                else:
                    axes, columns = axes + name[0], [*columns, start + k]
            out.append((j, axes, columns))
            start += len(names)
        return out

    def _full_euler(self, rotation_columns, frames):
        for j, axes, columns in rotation_columns:
            if axes and len(frames):
                euler = Rotation.from_euler(axes, frames[:, columns], degrees=True)
                self.local[:, j] = euler.as_matrix()

    def _by_axis(self, rotation_columns, frames):
        for slot in range(3):
            for axis in "XYZ":
                chosen = [
                    (j, c[slot]) for j, a, c in rotation_columns if a[slot : slot + 1] == axis
                ]
                if not chosen or not len(frames):
                    continue
                joints, columns = zip(*chosen, strict=True)
                angles = frames[:, list(columns)].reshape(-1, 1)
                elementary = Rotation.from_euler(axis, angles, degrees=True).as_matrix()
                elementary = elementary.reshape(frames.shape[0], len(joints), 3, 3)
                before = self.local[:, list(joints)]
                self.local[:, list(joints)] = elementary if slot == 0 else before @ elementary

    @staticmethod
    def wxyz(matrices):
        n_frames, n_joints = matrices.shape[:2]
        if n_frames * n_joints == 0:
            return np.zeros((n_frames, n_joints, 4))
        q = Rotation.from_matrix(matrices.reshape(-1, 3, 3)).as_quat()[:, [3, 0, 1, 2]]
        return q.reshape(n_frames, n_joints, 4)

    def end_sites(self, parents, offsets):
        out = np.zeros((self.pos.shape[0], len(parents), 3))
        for k, (p, o) in enumerate(zip(parents, offsets, strict=True)):
            out[:, k] = self.pos[:, p] + self.glob[:, p] @ np.asarray(o, dtype=float)
        return out


def reference_of(motion: Motion, full_euler: bool = False) -> ReferenceFK:
    sk = motion.skeleton
    return ReferenceFK(sk.parents, sk.offsets, sk.channels, motion.frames, full_euler)


def test_reference_modes_agree():
    """Single-axis products in declared order equal scipy's intrinsic Euler rotations."""
    rng = np.random.default_rng(11)
    case = bc.random_case(rng, 25, 30, position_prob=0.5)
    full = ReferenceFK(case.parents, case.offsets, case.channels, case.values, full_euler=True)
    split = ReferenceFK(case.parents, case.offsets, case.channels, case.values, full_euler=False)
    np.testing.assert_allclose(split.local, full.local, atol=1e-12)
    np.testing.assert_allclose(split.pos, full.pos, atol=1e-9)
    motion = read(UI_PRMD[0])
    short = motion.with_frames(motion.frames[::10])
    np.testing.assert_allclose(reference_of(short).pos, reference_of(short, True).pos, atol=1e-9)


def assert_same_rotations(ours, theirs, atol=1e-9):
    np.testing.assert_allclose(np.linalg.norm(ours, axis=-1), 1.0, atol=1e-12)
    sign = np.where(np.sum(ours * theirs, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    np.testing.assert_allclose(ours, sign * theirs, atol=atol)


def test_every_ui_prmd_file_matches_the_reference():
    assert len(UI_PRMD) == 200
    for path in UI_PRMD:
        motion = read(path)
        ref = reference_of(motion)
        np.testing.assert_allclose(kin.positions(motion), ref.pos, atol=TOL, err_msg=str(path))


def test_ui_prmd_rotations_and_end_sites():
    for path in UI_PRMD[::20]:
        motion = read(path)
        ref = reference_of(motion)
        assert_same_rotations(kin.rotations(motion), ref.wxyz(ref.local))
        assert_same_rotations(kin.global_rotations(motion), ref.wxyz(ref.glob))
        sk = motion.skeleton
        expected = ref.end_sites(sk.end_site_parents, sk.end_site_offsets)
        np.testing.assert_allclose(kin.end_site_positions(motion), expected, atol=TOL)


def check_case_against_reference(case: bc.Case) -> None:
    """Reference built from the generated case itself, not from what the parser made of it."""
    motion = read(case.text())
    ref = ReferenceFK(case.parents, case.offsets, case.channels, case.values)
    np.testing.assert_allclose(kin.positions(motion), ref.pos, atol=TOL)
    assert_same_rotations(kin.rotations(motion), ref.wxyz(ref.local))
    glob, pos = kin.world(motion)
    assert_same_rotations(glob, ref.wxyz(ref.glob))
    np.testing.assert_allclose(pos, ref.pos, atol=TOL)
    ends = ref.end_sites([p for p, _ in case.end_sites], [o for _, o in case.end_sites])
    np.testing.assert_allclose(kin.end_site_positions(motion), ends, atol=TOL)


@pytest.mark.parametrize("seed", range(12))
def test_random_skeletons_with_any_channel_layout(seed):
    rng = np.random.default_rng(1000 + seed)
    n_joints = int(rng.integers(1, 40))
    case = bc.random_case(rng, n_joints, n_frames=int(rng.integers(1, 40)), position_prob=0.4)
    check_case_against_reference(case)


@pytest.mark.parametrize("order", bc.TAIT_BRYAN_ORDERS)
def test_each_tait_bryan_order_on_a_chain(order):
    rng = np.random.default_rng(sum(map(ord, order)))
    rot = tuple(f"{a}rotation" for a in order)
    joints = [bc.JointSpec("root", -1, (1.0, 2.0, 3.0), (*bc.POSITIONS, *rot))]
    joints += [bc.JointSpec(f"j{k}", k - 1, (0.0, 10.0, 5.0), rot) for k in range(1, 5)]
    case = bc.Case(tuple(joints), ((4, (0.0, 3.0, 0.0)),), bc.random_tokens(rng, joints, 30))
    check_case_against_reference(case)


def test_partial_rotation_sets_and_position_only_joints():
    layouts = [("Yrotation",), ("Xrotation", "Zrotation"), ("Zposition", "Xposition"), ()]
    root = bc.JointSpec("root", -1, (0.0, 0.0, 0.0), ("Yposition", "Xrotation"))
    joints = [root] + [bc.JointSpec(f"j{k}", k, (3.0, 4.0, -5.0), c) for k, c in enumerate(layouts)]
    case = bc.Case(tuple(joints), (), bc.random_tokens(np.random.default_rng(2), joints, 25))
    check_case_against_reference(case)


@pytest.mark.parametrize("seed", range(3))
def test_nested_root_six_channels_everywhere_and_a_lying_rest_pose(seed):
    case = bc.bandai_like_case(np.random.default_rng(seed), n_frames=40)
    check_case_against_reference(case)
    pos = kin.positions(read(case.text()))
    np.testing.assert_allclose(pos[:, 0], 0.0)  # the static outer root stays put


def test_position_channels_replace_the_offset_on_their_axis_only():
    joints = (
        bc.JointSpec("root", -1, (0.0, 0.0, 0.0), ("Xrotation",)),
        bc.JointSpec("child", 0, (1.0, 2.0, 3.0), ("Yposition",)),
    )
    motion = read(bc.Case(joints, (), [["0", "7"]]).text())
    np.testing.assert_allclose(kin.positions(motion)[0, 1], [1.0, 7.0, 3.0])


# ---------------------------------------------------------------- hand-made arm


@pytest.fixture(scope="module")
def arm():
    return read(bc.arm_case([0.0, 90.0, 45.0, -90.0]).text())


def test_arm_positions_by_hand(arm):
    pos = kin.positions(arm)
    np.testing.assert_allclose(pos[:, 0], [[1, 2, 3]] * 4)
    np.testing.assert_allclose(pos[:, 1], [[1, -28, 3]] * 4)
    # Rz(90°) takes -y to +x: the forearm points along +x at 90°, along -x at -90°.
    np.testing.assert_allclose(pos[1, 2], [31, -28, 3], atol=1e-12)
    np.testing.assert_allclose(pos[3, 2], [-29, -28, 3], atol=1e-12)
    half = 30 / np.sqrt(2)
    np.testing.assert_allclose(pos[2, 2], [1 + half, -28 - half, 3], atol=1e-12)
    np.testing.assert_allclose(kin.end_site_positions(arm)[1, 0], [41, -28, 3], atol=1e-12)


def test_arm_joint_angles(arm):
    angles = kin.joint_angles(arm)
    assert set(angles) == {"Elbow", "Wrist"}  # the wrist's segments: forearm and hand (End Site)
    np.testing.assert_allclose(angles["Elbow"], [180.0, 90.0, 135.0, 90.0], atol=1e-9)
    np.testing.assert_allclose(angles["Wrist"], 180.0, atol=1e-6)


def test_arm_rotations(arm):
    q = kin.rotations(arm)
    assert q.shape == (4, 3, 4)
    s = np.sqrt(0.5)
    np.testing.assert_allclose(q[1, 1], [s, 0, 0, s], atol=1e-12)
    np.testing.assert_allclose(q[:, [0, 2]], np.broadcast_to([1.0, 0, 0, 0], (4, 2, 4)))
    np.testing.assert_allclose(kin.global_rotations(arm)[1, 2], [s, 0, 0, s], atol=1e-12)


def test_segment_angles_of_explicit_points():
    points = np.array([[[1.0, 0, 0], [0, 0, 0], [0, 2.0, 0], [-1.0, 0, 0]]])
    np.testing.assert_allclose(kin.segment_angles(points, [(0, 1, 2), (0, 1, 3)]), [[90, 180]])
    assert kin.segment_angles(points, []).shape == (1, 0)


# ---------------------------------------------------------------- normalisation


def test_root_relative_puts_the_root_at_the_origin():
    motion = read(UI_PRMD[0])
    pos = kin.positions(motion)
    rel = kin.root_relative(pos)
    np.testing.assert_allclose(rel[:, 0], 0.0)
    np.testing.assert_allclose(rel, pos - pos[:, :1])


def turn_root(channels, root_values, degrees):
    """Root channels after turning the whole performance by ``degrees`` about the world y axis."""
    turn = Rotation.from_euler("y", degrees, degrees=True)
    axes = "".join(c[0] for c in channels if c.endswith("rotation"))
    rot_cols = [k for k, c in enumerate(channels) if c.endswith("rotation")]
    pos_cols = [k for k, c in enumerate(channels) if c.endswith("position")]
    out = root_values.copy()
    turned = turn * Rotation.from_euler(axes, root_values[:, rot_cols], degrees=True)
    out[:, rot_cols] = turned.as_euler(axes, degrees=True)
    position = np.zeros((len(root_values), 3))
    position[:, ["XYZ".index(channels[k][0]) for k in pos_cols]] = root_values[:, pos_cols]
    out[:, pos_cols] = turn.apply(position)[:, ["XYZ".index(channels[k][0]) for k in pos_cols]]
    return out


@pytest.mark.parametrize("per_frame", [False, True])
def test_heading_normalisation_undoes_a_turn_about_the_vertical(per_frame):
    motion = read(UI_PRMD[0])
    n_root = len(motion.skeleton.channels[0])
    turned_root = turn_root(motion.skeleton.channels[0], motion.frames[:, :n_root], 30.0)
    turned = motion.with_frames(np.concatenate([turned_root, motion.frames[:, n_root:]], axis=1))
    # Really turned: the same skeleton, every joint rotated by 30° about y around the world origin.
    pos = kin.positions(motion)
    expected = Rotation.from_euler("y", 30, degrees=True).apply(pos.reshape(-1, 3))
    np.testing.assert_allclose(kin.positions(turned), expected.reshape(pos.shape), atol=1e-6)
    heading_gap = kin.heading_angles(turned) - kin.heading_angles(motion)
    np.testing.assert_allclose(np.angle(np.exp(1j * heading_gap)), np.radians(30), atol=1e-9)
    np.testing.assert_allclose(
        kin.normalised_positions(turned, per_frame=per_frame),
        kin.normalised_positions(motion, per_frame=per_frame),
        atol=1e-6,
    )


def test_heading_normalised_faces_a_common_direction():
    case = bc.arm_case([30.0, 60.0])
    tokens = [[*row[:5], "40", *row[6:]] for row in case.tokens]  # root heading 40° about y
    motion = read(bc.Case(case.joints, case.end_sites, tokens).text())
    np.testing.assert_allclose(np.degrees(kin.heading_angles(motion)), [40.0, 40.0], atol=1e-9)
    upright = read(case.text())
    np.testing.assert_allclose(
        kin.normalised_positions(motion, per_frame=True),
        kin.root_relative(kin.positions(upright)),
        atol=1e-9,
    )
    explicit = kin.heading_normalised(kin.positions(motion), np.radians(40.0))
    np.testing.assert_allclose(explicit, kin.root_relative(kin.positions(upright)), atol=1e-9)


def test_joints_must_follow_their_parents():
    motion = read(bc.SMALL)
    bad_skeleton = type(motion.skeleton)(
        names=motion.skeleton.names,
        parents=np.array([1, -1]),
        offsets=motion.skeleton.offsets,
        channels=motion.skeleton.channels,
        end_site_parents=motion.skeleton.end_site_parents,
        end_site_offsets=motion.skeleton.end_site_offsets,
    )
    with pytest.raises(ValueError, match="parent must come before"):
        kin.positions(Motion(bad_skeleton, motion.frames, motion.frame_time))
