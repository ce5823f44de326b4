"""A recording re-expressed on a Bandai-Namco-style rig, for tests (their files are CC BY-NC and
never copied here): a static ``joint_Root`` above the real root, six channels on every joint
(the position channels holding the joint's OFFSET), and a rest pose that is no posture at all:
every bone lies along its joint's local +x, so the rest figure lies flat and each joint's rest
frame is turned differently. The motion is the same: every joint's world position is unchanged.

How: each joint j gets a rest turn Q_j taking +x onto its first bone; its children's offsets are
expressed in that turned frame (Q_j^T · offset), and its local rotation becomes
Q_parent^T · L_j · Q_j, so the global rotations G_j · Q_j turn the new offsets back onto the old
bones (G_j · Q_j · Q_j^T · offset = G_j · offset).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from analysis.bvh import Motion, Skeleton
from analysis.kinematics import quaternions as quat
from analysis.kinematics.forward_kinematics import global_rotations

SIX = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")


def _along_x(direction: np.ndarray) -> np.ndarray:
    """The smallest rotation taking +x onto ``direction`` (identity when it has no length)."""
    norm = np.linalg.norm(direction)
    if norm < 1e-9:
        return np.eye(3)
    target = direction / norm
    axis = np.cross([1.0, 0.0, 0.0], target)
    angle = np.arctan2(np.linalg.norm(axis), target[0])
    if np.linalg.norm(axis) < 1e-12:
        return (
            np.eye(3) if target[0] > 0 else Rotation.from_euler("z", 180, degrees=True).as_matrix()
        )
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle).as_matrix()


def rest_turns(sk: Skeleton) -> list[np.ndarray]:
    """Per joint, the turn taking +x onto its first bone (a child's or End Site's offset)."""
    turns = []
    for j in range(len(sk.names)):
        bones = [sk.offsets[c] for c in sk.children(j)]
        bones += [
            o for p, o in zip(sk.end_site_parents, sk.end_site_offsets, strict=True) if p == j
        ]
        first = next((b for b in bones if np.linalg.norm(b) > 1e-9), np.zeros(3))
        turns.append(_along_x(first))
    return turns


def bandai_style(motion: Motion) -> Motion:
    """The motion on a Bandai-Namco-style skeleton (module docstring)."""
    sk = motion.skeleton
    turns = rest_turns(sk)
    parents = [int(p) for p in sk.parents]
    offsets = [
        sk.offsets[j] if p < 0 else turns[p].T @ sk.offsets[j] for j, p in enumerate(parents)
    ]
    skeleton = Skeleton(
        names=("joint_Root", *sk.names),
        parents=np.array([-1, *(p + 1 for p in parents)], dtype=np.int64),
        offsets=np.vstack([np.zeros(3), *offsets]),
        channels=(SIX,) * (len(sk.names) + 1),
        end_site_parents=sk.end_site_parents + 1,
        end_site_offsets=np.array(
            [turns[p].T @ o for p, o in zip(sk.end_site_parents, sk.end_site_offsets, strict=True)]
        ).reshape(-1, 3),
    )
    world = quat.to_matrix(global_rotations(motion))  # (F, J, 3, 3)
    columns = [np.zeros((motion.n_frames, 6))]
    for j, p in enumerate(parents):
        parent = np.eye(3) if p < 0 else world[:, p] @ turns[p]
        local = np.swapaxes(parent, -1, -2) @ world[:, j] @ turns[j]
        euler = Rotation.from_matrix(local).as_euler("ZXY", degrees=True)
        position = np.broadcast_to(offsets[j], (motion.n_frames, 3))
        if p < 0:  # the real root moves: its translation channels, in the static root's frame
            start = int(sk.channel_starts[j])
            names = sk.channels[j]
            position = np.stack(
                [motion.frames[:, start + names.index(f"{a}position")] for a in "XYZ"], axis=1
            )
        columns.append(np.hstack([position, euler]))
    return Motion(skeleton, np.hstack(columns), motion.frame_time)
