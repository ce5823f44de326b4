"""Retargeting a recording onto an exercise's skeleton: `map_onto`.

A recording made with the exercise's own rig (every joint of the exercise skeleton present under
the same name and parent) is returned unchanged. Any other rig is retargeted by segment rotations:

1. `analysis.bvh.rigs.correspond` pairs body parts (hips, chest, knees, …) of the two skeletons
   by names and structure; it raises `SkeletonMismatchError` naming missing parts in plain words.
2. Every exercise joint gets a *source point* per frame: the recording's position of the same body
   part, or, for a joint without a counterpart (extra or missing spine, neck or collarbone joints),
   the point at the same fraction of rest length along the recording's chain between the nearest
   matched joints above and below it.
3. The recording's world is turned so that its up axis (mean hips → chest direction over the take,
   snapped to ±x/±y/±z: Z-up rigs) becomes the exercise skeleton's.
4. Each exercise joint's global rotation takes the directions of its bones *in the exercise
   skeleton's rest pose* onto the recording's world directions between the corresponding source
   points: a best-fit rotation (Kabsch) where a joint has two or more bones (hips, chest);
   otherwise the recording joint's own rotation, corrected once for the difference between the two
   rest poses (T-pose vs A-pose, other bone directions) and then by the smallest rotation that
   lands the bone exactly, so the twist about the bone follows the recording.
5. Local rotations are written as Euler angles in each exercise joint's declared channel order;
   the root translation is the recording's hips, scaled to the exercise skeleton's size. Bone
   lengths are the recording's (scaled the same way), as with a recording from the same rig.

The result is a `Motion` whose skeleton has exactly the exercise skeleton's joints, names, parents
and channels, so every later stage is unchanged.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from analysis.bvh import rigs
from analysis.bvh.io import Motion, Skeleton
from analysis.kinematics import quaternions as quat
from analysis.kinematics.forward_kinematics import world

FloatArray = npt.NDArray[np.float64]
_AXES = np.eye(3)


def same_rig(source: Skeleton, target: Skeleton) -> bool:
    """Every target joint is in the source under the same name, with the same parent name."""
    index = {n: k for k, n in enumerate(source.names)}
    for name, parent in zip(target.names, target.parents, strict=True):
        if name not in index:
            return False
        own_parent = int(source.parents[index[name]])
        wanted = target.names[int(parent)] if parent >= 0 else None
        if (source.names[own_parent] if own_parent >= 0 else None) != wanted:
            return False
    return True


def map_onto(motion: Motion, target: Skeleton) -> Motion:
    """The recording on the exercise skeleton ``target`` (see the module docstring).

    Raises SkeletonMismatchError (a ValueError) when the body parts cannot be matched; its message
    names the missing parts in plain words and says what to do.
    """
    if same_rig(motion.skeleton, target):
        return motion
    pairs = rigs.correspond(motion.skeleton, target)
    return _Retarget(motion, target, pairs).run()


# ------------------------------------------------------------------ rotation helpers


def _unit(v: FloatArray) -> FloatArray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _skew(v: FloatArray) -> FloatArray:
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def min_rotation(a: FloatArray, b: FloatArray) -> FloatArray:
    """The smallest rotation matrices taking directions a onto b: (..., 3) → (..., 3, 3)."""
    a, b = np.broadcast_arrays(_unit(np.asarray(a, float)), _unit(np.asarray(b, float)))
    v = np.cross(a, b)
    c = np.sum(a * b, axis=-1)
    k = _skew(v)
    scale = 1.0 / np.maximum(1.0 + c, 1e-12)
    out = np.eye(3) + k + (k @ k) * scale[..., None, None]
    opposite = c < -1.0 + 1e-9
    if np.any(opposite):
        # Half a turn about any axis perpendicular to a.
        helper = np.where(np.abs(a[..., :1]) < 0.9, _AXES[0], _AXES[1])
        axis = _unit(np.cross(a, helper))
        half = 2.0 * axis[..., :, None] * axis[..., None, :] - np.eye(3)
        out = np.where(opposite[..., None, None], half, out)
    return out


def best_rotation(u: FloatArray, d: FloatArray) -> FloatArray:
    """Rotations R (F, 3, 3) minimising Σ|R u_k − d_k|² for u (K, 3) and d (F, K, 3) (Kabsch)."""
    h = np.einsum("ki,fkj->fij", u, d)
    left, _, right_t = np.linalg.svd(h)
    det = np.sign(np.linalg.det(right_t.transpose(0, 2, 1) @ left.transpose(0, 2, 1)))
    fix = np.ones((h.shape[0], 3))
    fix[:, 2] = np.where(det == 0, 1.0, det)
    return (right_t.transpose(0, 2, 1) * fix[:, None, :]) @ left.transpose(0, 2, 1)


def snapped_axis(v: FloatArray) -> FloatArray:
    """The signed coordinate axis nearest to direction v."""
    k = int(np.argmax(np.abs(v)))
    return _AXES[k] * (1.0 if v[k] >= 0 else -1.0)


# ------------------------------------------------------------------ the retargeting


class _Retarget:
    def __init__(self, motion: Motion, target: Skeleton, pairs: dict[str, tuple[int, int]]):
        self.motion, self.target = motion, target
        self.source = motion.skeleton
        self.match = {t: s for t, s in pairs.values()}  # target joint → source point
        glob, pos = world(motion)
        sk = self.source
        ends = pos[:, sk.end_site_parents] + _rotate(
            glob[:, sk.end_site_parents], sk.end_site_offsets
        )
        self.points = np.concatenate((pos, ends), axis=1)
        self.rest = rigs.rest_points(sk)[None]
        self.glob_q = glob
        self.parents = [int(p) for p in target.parents]
        self.children = [target.children(j) for j in range(len(target.names))]
        self.pelvis, self.chest = pairs["pelvis"], pairs["chest"]

    # -- source points for every target joint

    def _source_path(self, a: int, b: int) -> list[int]:
        """Point indices from source point a to b through the tree (End Sites only at the ends)."""
        n = len(self.source.names)
        parents = [int(p) for p in self.source.parents]
        ja = a if a < n else int(self.source.end_site_parents[a - n])
        jb = b if b < n else int(self.source.end_site_parents[b - n])
        top = rigs.common_ancestor(parents, ja, jb)
        up = rigs._ancestors(parents, ja)
        down = rigs._ancestors(parents, jb)
        path = up[: up.index(top) + 1] + list(reversed(down[: down.index(top)]))
        if a >= n:
            path.insert(0, a)
        if b >= n:
            path.append(b)
        return path

    def _nearest_matched_below(self, joint: int) -> int | None:
        queue = list(self.children[joint])
        while queue:
            nxt = []
            for c in queue:
                if c in self.match:
                    return c
                nxt += self.children[c]
            queue = nxt
        return None

    def _target_points(self, cloud: FloatArray) -> list[FloatArray | None]:
        """Per target joint, its source point (F, 3) in ``cloud`` (F, P, 3), or None."""
        target = self.target
        lengths = np.linalg.norm(target.offsets, axis=1)
        out: list[FloatArray | None] = []
        for j in range(len(target.names)):
            if j in self.match:
                out.append(cloud[:, self.match[j]])
                continue
            above = self.parents[j]
            while above >= 0 and above not in self.match:
                above = self.parents[above]
            below = self._nearest_matched_below(j)
            if above < 0 or below is None:
                out.append(None)
                continue
            chain = rigs._ancestors(self.parents, below)
            chain = chain[: chain.index(above)]  # below … up to (excluding) above
            total = float(sum(lengths[c] for c in chain))
            done = float(sum(lengths[c] for c in chain if rigs.is_ancestor(self.parents, c, j)))
            fraction = done / total if total > 1e-12 else 0.5
            out.append(self._along(cloud, self.match[above], self.match[below], fraction))
        return out

    def _along(self, cloud: FloatArray, a: int, b: int, fraction: float) -> FloatArray:
        """The point at ``fraction`` of the rest length along the source chain from a to b."""
        path = self._source_path(a, b)
        rest = self.rest[0, path]
        seg = np.linalg.norm(np.diff(rest, axis=0), axis=1)
        if seg.sum() < 1e-12:
            return cloud[:, a]
        at = fraction * seg.sum()
        cumulative = np.concatenate(([0.0], np.cumsum(seg)))
        k = int(np.clip(np.searchsorted(cumulative, at, side="right") - 1, 0, len(seg) - 1))
        t = (at - cumulative[k]) / seg[k] if seg[k] > 1e-12 else 0.0
        return (1 - t) * cloud[:, path[k]] + t * cloud[:, path[k + 1]]

    # -- orientation and size

    def _world_turn(self) -> FloatArray:
        """Rotation taking the recording's up axis onto the exercise skeleton's."""
        hips, chest = self.pelvis[1], self.chest[1]
        spine = np.mean(_unit(self.points[:, chest] - self.points[:, hips]), axis=0)
        rest_t = rigs.rest_points(self.target)
        up_t = snapped_axis(rest_t[self.chest[0]] - rest_t[self.pelvis[0]])
        return min_rotation(snapped_axis(spine), up_t)

    def run(self) -> Motion:
        turn = self._world_turn()
        cloud = self.points @ turn.T
        rest_cloud = self.rest @ turn.T
        # Matrices only for the recording's matched joints: (F, J, 3, 3) for a long take of a
        # 60-joint rig would cost hundreds of megabytes.
        n_joints = len(self.source.names)
        glob = {
            s: turn @ _matrices(self.glob_q[:, s]) @ turn.T
            for s in self.match.values()
            if s < n_joints
        }
        points = self._target_points(cloud)
        rest_points = self._target_points(rest_cloud)
        offsets, scale = self._offsets(rest_points)
        world_rot = self._rotations(points, glob, rest_points, offsets)
        return self._motion(world_rot, points, offsets, scale)

    def _offsets(self, rest_points: list[FloatArray | None]) -> tuple[FloatArray, float]:
        """Target offsets with the recording's bone lengths, scaled to the target's size."""
        target = self.target
        offsets = target.offsets.copy()
        pairs = []
        for j, p in enumerate(self.parents):
            a, b = rest_points[j], rest_points[p] if p >= 0 else None
            if p >= 0 and a is not None and b is not None:
                pairs.append((j, float(np.linalg.norm(a[0] - b[0]))))
        own = sum(np.linalg.norm(target.offsets[j]) for j, _ in pairs)
        theirs = sum(length for _, length in pairs)
        scale = float(own / theirs) if theirs > 1e-12 else 1.0
        for j, length in pairs:
            norm = np.linalg.norm(target.offsets[j])
            if norm > 1e-9:
                offsets[j] = target.offsets[j] / norm * length * scale
        self._hub_offsets(offsets, rest_points, scale)
        return offsets, scale

    def _hub_offsets(
        self, offsets: FloatArray, rest_points: list[FloatArray | None], scale: float
    ) -> None:
        """Bones of joints with several (hips, chest): the recording's rest geometry, turned into
        the exercise skeleton's rest frame, so a best-fit rotation lands every bone exactly."""
        for j, children in enumerate(self.children):
            here = rest_points[j]
            kids = [
                c for c in children if rest_points[c] is not None and np.linalg.norm(offsets[c])
            ]
            if here is None or len(kids) < 2 or not _spread(offsets[kids]):
                continue
            theirs = np.stack([rest_points[c][0] - here[0] for c in kids])  # type: ignore[index]
            if not _spread(theirs):
                continue
            turn = best_rotation(offsets[kids], theirs[None])[0]
            offsets[kids] = theirs @ turn * scale

    def _rotations(
        self,
        points: list[FloatArray | None],
        glob: dict[int, FloatArray],
        rest_points: list[FloatArray | None],
        offsets: FloatArray,
    ) -> FloatArray:
        """Global rotation matrices (F, J, 3, 3) of the target joints."""
        n_frames, n_joints = self.motion.n_frames, len(self.target.names)
        out = np.empty((n_frames, n_joints, 3, 3))
        correction: dict[int, FloatArray] = {}
        for j in range(n_joints):
            parent = self.parents[j]
            base = out[:, parent] if parent >= 0 else np.broadcast_to(np.eye(3), (n_frames, 3, 3))
            own = self.match.get(j, -1)
            own_rot = glob.get(own)
            kids = [c for c in self.children[j] if points[c] is not None
                    and np.linalg.norm(offsets[c]) > 1e-9]  # fmt: skip
            here = points[j]
            if here is None or not kids:
                if own_rot is not None:
                    fix = correction.get(parent, np.eye(3))
                    out[:, j] = own_rot @ fix
                else:
                    out[:, j] = base
                continue
            u = offsets[kids]
            d = np.stack([points[c] - here for c in kids], axis=1)  # type: ignore[operator]
            if len(kids) >= 2 and _spread(u):
                lengths = np.linalg.norm(u, axis=1)
                out[:, j] = best_rotation(u, _unit(d) * lengths[None, :, None])
                continue
            longest = int(np.argmax(np.linalg.norm(u, axis=1)))
            u1, d1 = u[longest], d[:, longest]
            if own_rot is not None:
                rest_here, rest_kid = rest_points[j], rest_points[kids[longest]]
                assert rest_here is not None and rest_kid is not None
                fix = min_rotation(u1, (rest_kid - rest_here)[0])
                correction[j] = fix
                guess = own_rot @ fix
            else:
                guess = base.copy()
            out[:, j] = min_rotation(guess @ u1, d1) @ guess
        return out

    def _motion(
        self,
        world_rot: FloatArray,
        points: list[FloatArray | None],
        offsets: FloatArray,
        scale: float,
    ) -> Motion:
        target = self.target
        n_frames = world_rot.shape[0]
        frames = np.zeros((n_frames, target.n_channels))
        starts = target.channel_starts  # worked out on each read: once here, not per joint
        for j, channels in enumerate(target.channels):
            parent = self.parents[j]
            local = world_rot[:, j]
            if parent >= 0:
                local = world_rot[:, parent].transpose(0, 2, 1) @ local
            start = int(starts[j])
            axes = "".join(c[0] for c in channels if c.endswith("rotation"))
            if axes:
                angles = quat.matrix_to_euler(local, quat.complete_order(axes))
            for k, channel in enumerate(channels):
                axis = "XYZ".index(channel[0])
                if channel.endswith("rotation"):
                    frames[:, start + k] = angles[:, axes.index(channel[0])]
                elif parent < 0 and points[j] is not None:
                    frames[:, start + k] = points[j][:, axis] * scale  # type: ignore[index]
                else:
                    frames[:, start + k] = offsets[j, axis]
        skeleton = Skeleton(
            names=target.names,
            parents=target.parents,
            offsets=offsets,
            channels=target.channels,
            end_site_parents=target.end_site_parents,
            end_site_offsets=target.end_site_offsets,
        )
        return Motion(skeleton, frames, self.motion.frame_time, self.motion.warnings)


def _spread(u: FloatArray) -> bool:
    """Whether bone directions u (K, 3) span more than a line (a rotation is then determined)."""
    unit = _unit(u)
    return bool(np.max(np.linalg.norm(np.cross(unit[:, None], unit[None]), axis=-1)) > 0.2)


def _matrices(q: FloatArray) -> FloatArray:
    return quat.to_matrix(q)


def _rotate(q: FloatArray, v: FloatArray) -> FloatArray:
    return quat.rotate(q, v)
