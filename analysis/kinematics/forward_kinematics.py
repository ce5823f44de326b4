"""Forward kinematics of a BVH `Motion`: local and global rotations, world positions, joint angles,
normalisation (root-relative, heading) and resampling to another frame rate.

Conventions: BVH rotation channels are intrinsic and applied in the declared order, so channels
``Zrotation Xrotation Yrotation`` give R = Rz·Rx·Ry. Position channels, where a joint has them, give
its translation relative to the parent on those axes (replacing the OFFSET component, as exporters
that write 6 channels on every joint expect); other axes keep the OFFSET. Quaternions are unit
(w, x, y, z). The vertical axis is y.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import numpy.typing as npt

from analysis.bvh.io import Motion, Skeleton
from analysis.kinematics import point_kernels
from analysis.kinematics import quaternion_kernels as quat_kernels
from analysis.kinematics import quaternions as quat

FloatArray = npt.NDArray[np.float64]
UP_AXIS = 1


def _rotation_layout(skeleton: Skeleton) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Per joint, up to 3 rotation columns and their axes (0..2) in declared order; -1: none."""
    columns = np.full((len(skeleton.names), 3), -1, dtype=np.int64)
    axes = np.full((len(skeleton.names), 3), -1, dtype=np.int64)
    for joint, (start, channels) in enumerate(
        zip(skeleton.channel_starts, skeleton.channels, strict=True)
    ):
        rotation = [(int(start) + k, "XYZ".index(c[0])) for k, c in enumerate(channels)
                    if c.endswith("rotation")]  # fmt: skip
        for slot, (column, axis) in enumerate(rotation):
            columns[joint, slot], axes[joint, slot] = column, axis
    return columns, axes


# "afn" lets LLVM fetch each angle's cosine and sine with one sincos call (the same values on
# every UI-PRMD file and the synthetic bench file, about 10 % of the positions' time).
@numba.njit(cache=True, nogil=True, fastmath={"afn"})
def _local_quaternion(
    row: FloatArray, columns: npt.NDArray[np.int64], axes: npt.NDArray[np.int64]
) -> tuple[float, float, float, float]:
    """One joint's rotation from its (up to 3) Euler channels in one frame row, as (w, x, y, z)."""
    w, x, y, z = 1.0, 0.0, 0.0, 0.0
    half = np.pi / 360.0
    for slot in range(3):
        if columns[slot] < 0:
            break
        angle = row[columns[slot]] * half
        # a channel held at 0 (a still joint): cos(±0) = 1 and sin(±0) = ±0 exactly
        c, s = (1.0, angle) if angle == 0.0 else (np.cos(angle), np.sin(angle))
        # Right-multiply by the elementary rotation: intrinsic order as declared.
        if axes[slot] == 0:
            w, x, y, z = w * c - x * s, x * c + w * s, y * c + z * s, z * c - y * s
        elif axes[slot] == 1:
            w, x, y, z = w * c - y * s, x * c - z * s, y * c + w * s, z * c + x * s
        else:
            w, x, y, z = w * c - z * s, x * c + y * s, y * c - x * s, z * c + w * s
    return w, x, y, z


@numba.njit(cache=True, nogil=True)
def _euler_quaternions(
    frames: FloatArray, columns: npt.NDArray[np.int64], axes: npt.NDArray[np.int64]
) -> FloatArray:
    n_frames, n_joints = frames.shape[0], columns.shape[0]
    out = np.empty((n_frames, n_joints, 4))
    for f in range(n_frames):
        for j in range(n_joints):
            w, x, y, z = _local_quaternion(frames[f], columns[j], axes[j])
            out[f, j, 0], out[f, j, 1], out[f, j, 2], out[f, j, 3] = w, x, y, z
    return out


def rotations(motion: Motion) -> FloatArray:
    """Local joint rotations relative to the parent: (F, J, 4) unit quaternions (w, x, y, z)."""
    return _rotations(motion)


def _rotations(motion: Motion) -> FloatArray:
    columns, axes = _rotation_layout(motion.skeleton)
    return _euler_quaternions(np.ascontiguousarray(motion.frames), columns, axes)


def translations(motion: Motion) -> FloatArray:
    """Each joint's translation from its parent per frame: (F, J, 3) file units."""
    skeleton = motion.skeleton
    out = np.broadcast_to(skeleton.offsets, (motion.n_frames, *skeleton.offsets.shape)).copy()
    for joint, (start, channels) in enumerate(
        zip(skeleton.channel_starts, skeleton.channels, strict=True)
    ):
        for k, channel in enumerate(channels):
            if channel.endswith("position"):
                out[:, joint, "XYZ".index(channel[0])] = motion.frames[:, int(start) + k]
    return out


@numba.njit(cache=True, nogil=True)
def _compose(a: FloatArray, b: tuple[float, float, float, float], out: FloatArray) -> None:
    """out = a·b for quaternions (w, x, y, z)."""
    aw, ax, ay, az = a[0], a[1], a[2], a[3]
    bw, bx, by, bz = b
    out[0] = aw * bw - ax * bx - ay * by - az * bz
    out[1] = aw * bx + ax * bw + ay * bz - az * by
    out[2] = aw * by - ax * bz + ay * bw + az * bx
    out[3] = aw * bz + ax * by - ay * bx + az * bw


@numba.njit(cache=True, nogil=True)
def _place(a: FloatArray, base: FloatArray, t: tuple[float, float, float], out: FloatArray) -> None:
    """out = base + a applied to t: v' = v + w·c + u × c with c = 2 u × v."""
    aw, ax, ay, az = a[0], a[1], a[2], a[3]
    tx, ty, tz = t
    cx, cy, cz = 2 * (ay * tz - az * ty), 2 * (az * tx - ax * tz), 2 * (ax * ty - ay * tx)
    out[0] = base[0] + tx + aw * cx + (ay * cz - az * cy)
    out[1] = base[1] + ty + aw * cy + (az * cx - ax * cz)
    out[2] = base[2] + tz + aw * cz + (ax * cy - ay * cx)


@numba.njit(cache=True, nogil=True)
def _chain_frame(
    q: FloatArray, t: FloatArray, parents: npt.NDArray[np.int64], glob: FloatArray, pos: FloatArray
) -> None:
    """One frame down the chain: (J, 4) local rotations and (J, 3) translations into (J, 4)
    world rotations and (J, 3) world positions (parents before children)."""
    for j in range(q.shape[0]):
        p = parents[j]
        bw, bx, by, bz = q[j, 0], q[j, 1], q[j, 2], q[j, 3]
        tx, ty, tz = t[j, 0], t[j, 1], t[j, 2]
        if p < 0:
            glob[j, 0], glob[j, 1], glob[j, 2], glob[j, 3] = bw, bx, by, bz
            pos[j, 0], pos[j, 1], pos[j, 2] = tx, ty, tz
            continue
        _compose(glob[p], (bw, bx, by, bz), glob[j])
        _place(glob[p], pos[p], (tx, ty, tz), pos[j])


@numba.njit(cache=True, nogil=True)
def _chain(
    local_q: FloatArray, local_t: FloatArray, parents: npt.NDArray[np.int64]
) -> tuple[FloatArray, FloatArray]:
    glob = np.empty_like(local_q)
    pos = np.empty_like(local_t)
    for f in range(local_q.shape[0]):
        _chain_frame(local_q[f], local_t[f], parents, glob[f], pos[f])
    return glob, pos


@numba.njit(cache=True, nogil=True)
def _positions_only(
    frames: FloatArray,
    layout: npt.NDArray[np.int64],
    offsets: FloatArray,
    parents: npt.NDArray[np.int64],
) -> FloatArray:
    """`_euler_quaternions` + `_chain` one frame at a time, keeping only the positions: the
    (F, J, 4) intermediates cost more in memory traffic and page faults than the arithmetic.
    ``layout`` (J, 9): rotation columns, their axes, translation columns (-1: none). A joint
    that is no joint's parent needs no rotation (it moves no other joint): its sines and
    cosines, a large part of the work, are skipped."""
    n_frames, n_joints = frames.shape[0], parents.shape[0]
    pos = np.empty((n_frames, n_joints, 3))
    glob = np.empty((n_joints, 4))
    is_parent = np.zeros(n_joints, np.bool_)
    for j in range(n_joints):
        if parents[j] >= 0:
            is_parent[parents[j]] = True
    t = np.empty(3)
    for f in range(n_frames):
        row = frames[f]
        for j in range(n_joints):
            for k in range(3):
                column = layout[j, 6 + k]
                t[k] = row[column] if column >= 0 else offsets[j, k]
            p = parents[j]
            if p >= 0:
                _place(glob[p], pos[f, p], (t[0], t[1], t[2]), pos[f, j])
            else:
                pos[f, j, 0], pos[f, j, 1], pos[f, j, 2] = t[0], t[1], t[2]
            if not is_parent[j]:
                continue
            local = _local_quaternion(row, layout[j, 0:3], layout[j, 3:6])
            if p < 0:
                glob[j, 0], glob[j, 1], glob[j, 2], glob[j, 3] = local
            else:
                _compose(glob[p], local, glob[j])
    return pos


def _check_parent_order(skeleton: Skeleton) -> None:
    if np.any(skeleton.parents >= np.arange(len(skeleton.names))):
        raise ValueError("every joint's parent must come before it")


def forward(
    skeleton: Skeleton, local_q: FloatArray, local_t: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Global rotations (F, J, 4) and world positions (F, J, 3) from local rotations (F, J, 4)
    and translations (F, J, 3): for poses that were edited as rotations (adjustment, playback)."""
    _check_parent_order(skeleton)
    q = np.ascontiguousarray(local_q, dtype=np.float64)
    t = np.ascontiguousarray(local_t, dtype=np.float64)
    return _chain(q, t, skeleton.parents)


def forward_positions(skeleton: Skeleton, local_q: FloatArray, local_t: FloatArray) -> FloatArray:
    """``forward(...)[1]`` (the same bits) without the (F, J, 4) global rotations: each frame's
    are kept in a (J, 4) scratch, which saves their memory traffic (the playback skeletons)."""
    _check_parent_order(skeleton)
    q = np.ascontiguousarray(local_q, dtype=np.float64)
    t = np.ascontiguousarray(local_t, dtype=np.float64)
    return _chain_positions(q, t, skeleton.parents)


@numba.njit(cache=True, nogil=True)
def _chain_positions(
    local_q: FloatArray, local_t: FloatArray, parents: npt.NDArray[np.int64]
) -> FloatArray:
    """`_chain`'s positions: the same products in the same order, frame by frame."""
    glob = np.empty((local_q.shape[1], 4))
    pos = np.empty_like(local_t)
    for f in range(local_q.shape[0]):
        _chain_frame(local_q[f], local_t[f], parents, glob, pos[f])
    return pos


def world(motion: Motion) -> tuple[FloatArray, FloatArray]:
    """Global rotations (F, J, 4) and world positions (F, J, 3) in one pass."""
    return forward(motion.skeleton, rotations(motion), translations(motion))


def _translation_columns(skeleton: Skeleton) -> npt.NDArray[np.int64]:
    """(J, 3): the frame column giving each joint's x/y/z translation, -1 where the OFFSET does."""
    out = np.full((len(skeleton.names), 3), -1, dtype=np.int64)
    for joint, (start, channels) in enumerate(
        zip(skeleton.channel_starts, skeleton.channels, strict=True)
    ):
        for k, channel in enumerate(channels):
            if channel.endswith("position"):
                out[joint, "XYZ".index(channel[0])] = int(start) + k
    return out


def positions(motion: Motion) -> FloatArray:
    """World positions of every joint: (F, J, 3), same units as the file."""
    return _positions(motion)


def _positions(motion: Motion) -> FloatArray:
    skeleton = motion.skeleton
    _check_parent_order(skeleton)
    columns, axes = _rotation_layout(skeleton)
    layout = np.hstack([columns, axes, _translation_columns(skeleton)])
    frames = np.ascontiguousarray(motion.frames, dtype=np.float64)
    offsets = np.ascontiguousarray(skeleton.offsets, dtype=np.float64)
    return _positions_only(frames, layout, offsets, skeleton.parents)


@dataclass(frozen=True, eq=False)
class Kinematics:
    """One recording's forward kinematics, computed once (`kinematics`) and handed to every
    stage that needs it: ``local_q`` (F, J, 4) local rotations, ``local_t`` (F, J, 3)
    translations from the parent, ``global_q`` (F, J, 4) world rotations, ``positions``
    (F, J, 3) world positions (file units), ``facing`` (F, J, 3) root-relative positions facing
    the recording's mean heading (`heading_facing`, read-only): the scaled positions, the
    key-pose signature and the pose series all start from them."""

    local_q: FloatArray
    local_t: FloatArray
    global_q: FloatArray
    positions: FloatArray
    facing: FloatArray

    @property
    def heading(self) -> FloatArray:
        """The root's heading per frame, radians: (F,) (as `heading_angles`)."""
        return _root_heading(self.local_q)


def _root_heading(local_q: FloatArray) -> FloatArray:
    return quat.twist_angle(local_q[:, 0], "XYZ"[UP_AXIS])


def kinematics(motion: Motion) -> Kinematics:
    """Every frame's rotations and positions in one forward-kinematics pass, and the positions
    facing the mean heading: made here with the rest rather than on first read, so the object
    holds nothing that appears later (the few callers that never read them, such as the live
    session's once-a-repetition catch-up, pay a small rotation of points they already have)."""
    local_q, local_t = _rotations(motion), translations(motion)
    global_q, pos = forward(motion.skeleton, local_q, local_t)
    facing = heading_facing(pos, _root_heading(local_q))
    facing.setflags(write=False)
    return Kinematics(local_q, local_t, global_q, pos, facing)


def global_rotations(motion: Motion) -> FloatArray:
    """Rotations of every joint in the world frame: (F, J, 4) unit quaternions."""
    return world(motion)[0]


def end_site_positions(motion: Motion) -> FloatArray:
    """World positions of the End Sites: (F, E, 3)."""
    glob, pos = world(motion)
    parents = motion.skeleton.end_site_parents
    offsets = motion.skeleton.end_site_offsets
    return pos[:, parents] + quat.rotate(glob[:, parents], offsets[None])


def segment_angles(points: FloatArray, triples: list[tuple[int, int, int]]) -> FloatArray:
    """Angle in degrees at b between segments b→a and b→c for each (a, b, c): (F, len(triples))."""
    if not triples:
        return np.zeros((points.shape[0], 0))
    a, b, c = (np.array(t, dtype=np.int64) for t in zip(*triples, strict=True))
    points = np.ascontiguousarray(points, dtype=np.float64)
    return np.degrees(point_kernels.angles_at(points, a, b, c))


def angle_triples(skeleton: Skeleton) -> list[tuple[int, int, int]]:
    """(parent, joint, child) for every joint with a parent and a child joint or End Site.

    End Site k is numbered J + k, as in the point array of `joint_angles`.
    """
    n_joints = len(skeleton.names)
    triples = []
    for joint, parent in enumerate(skeleton.parents):
        children = skeleton.children(joint)
        children += [n_joints + int(k) for k in np.flatnonzero(skeleton.end_site_parents == joint)]
        if parent >= 0 and children:
            triples.append((int(parent), joint, children[0]))
    return triples


def joint_angles(motion: Motion, kin: Kinematics | None = None) -> dict[str, FloatArray]:
    """Angle (degrees, 180 = straight) between the segments meeting at each joint: {name: (F,)};
    ``kin``: the motion's `kinematics` when already computed."""
    glob, pos = world(motion) if kin is None else (kin.global_q, kin.positions)
    sk = motion.skeleton
    ends = pos[:, sk.end_site_parents] + quat.rotate(
        glob[:, sk.end_site_parents], sk.end_site_offsets
    )
    triples = angle_triples(sk)
    values = segment_angles(np.concatenate((pos, ends), axis=1), triples)
    return {sk.names[t[1]]: values[:, k] for k, t in enumerate(triples)}


def root_relative(points: FloatArray) -> FloatArray:
    """Positions relative to the root joint (joint 0) of each frame: (F, J, 3)."""
    return points - points[:, :1]


def heading_angles(motion: Motion) -> FloatArray:
    """The root's heading (rotation about the vertical axis) per frame, radians: (F,)."""
    columns, axes = _rotation_layout(motion.skeleton)
    frames = np.ascontiguousarray(motion.frames)
    root = _euler_quaternions(frames, columns[:1], axes[:1])[:, 0]  # the root's alone: 1/J the work
    return quat.twist_angle(root, "XYZ"[UP_AXIS])


def heading_normalised(points: FloatArray, heading: FloatArray | float) -> FloatArray:
    """Root-relative positions turned about the vertical so the heading becomes 0: (F, J, 3)."""
    heading = np.broadcast_to(np.asarray(heading, dtype=np.float64), points.shape[:1])
    undo = quat.from_axis_angle("XYZ"[UP_AXIS], -heading)
    points = np.ascontiguousarray(points, dtype=np.float64)
    return quat_kernels.turn_root_relative(np.ascontiguousarray(undo), points)


def normalised_positions(motion: Motion, per_frame: bool = False) -> FloatArray:
    """Root-relative positions facing a common heading: (F, J, 3).

    By default one heading per recording (the circular mean over frames) is removed, so turning of
    the trunk during the exercise is kept; ``per_frame`` removes each frame's own heading.
    """
    return heading_facing(_positions(motion), heading_angles(motion), per_frame)


def heading_facing(points: FloatArray, heading: FloatArray, per_frame: bool = False) -> FloatArray:
    """`normalised_positions` from world positions (F, J, 3) and the root's heading (F,)."""
    if not per_frame:
        heading = np.full_like(heading, np.angle(np.mean(np.exp(1j * heading))))
    return heading_normalised(points, heading)
