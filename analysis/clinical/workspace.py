"""Reachable workspace of each hand: the share of the frontal hemisphere around the shoulder that
the hand's path covers, in total and per quadrant (Kurillo et al., "Upper extremity reachable
workspace evaluation with Kinect", Stud. Health Technol. Inform. 2013; Kurillo et al., PLoS ONE
2012, doi:10.1371/journal.pone.0045341).

The wrist's path is taken relative to its shoulder in the thorax frame (so leaning the trunk is
not reach) and divided by the arm's length (upper arm + forearm); axes X anterior, Y superior,
Z lateral (mirrored for the left side, so lateral is away from the body on both). Every position
is projected radially onto the unit sphere, and the convex hull of those directions and of the
shoulder (trimesh) gives the covered patch: the hull's faces away from the shoulder. Its area on
the sphere is the sum of the faces' solid angles (exact for the hull's radial projection). Only
the frontal hemisphere (X ≥ 0, in front of the frontal plane through the shoulder) counts, as
in Kurillo's protocol where the sensor faces the patient; it is cut by the horizontal plane
(upper / lower) and the sagittal plane through the shoulder (medial / lateral) into four
quadrants. Areas are relative to the hemisphere (2π sr): the total is 0..1, each quadrant
0..0.25, and the four add up to the total.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import trimesh
from scipy.spatial import QhullError

from analysis.bvh import Motion
from analysis.clinical.body import (
    SIDE_SIGN,
    SIDES,
    Body,
    FloatArray,
    find_body,
    geometry,
    unit,
)
from analysis.kinematics import Kinematics, kinematics

IntArray = npt.NDArray[np.int64]
HEMISPHERE_SR = 2.0 * np.pi
# name -> (normal of the Y cut, normal of the Z cut): the half-spaces n · v ≥ 0 it lies in.
QUADRANTS: dict[str, tuple[float, float]] = {
    "upper_medial": (1.0, -1.0),
    "upper_lateral": (1.0, 1.0),
    "lower_medial": (-1.0, -1.0),
    "lower_lateral": (-1.0, 1.0),
}


@dataclass(frozen=True)
class Workspace:
    """One hand's reachable workspace. ``vertices`` (V, 3) and ``faces`` (K, 3): the covered
    patch of the unit sphere (arm lengths; X anterior, Y superior, Z lateral) for a 3D view."""

    side: str
    relative_area: float
    quadrants: dict[str, float]
    vertices: FloatArray = field(repr=False)
    faces: IntArray = field(repr=False)
    arm_length: float = 1.0  # file units

    def to_json(self) -> dict[str, object]:
        return {
            "side": self.side,
            "relative_area": self.relative_area,
            "quadrants": dict(self.quadrants),
            "arm_length": self.arm_length,
            "vertices": np.round(self.vertices, 4).tolist(),
            "faces": self.faces.tolist(),
        }


def solid_angles(vertices: FloatArray, faces: IntArray) -> FloatArray:
    """Solid angle (sr) of each triangle seen from the origin (Van Oosterom & Strackee 1983)."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
    numerator = np.abs(np.einsum("ij,ij->i", a, np.cross(b, c)))
    dots = np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", a, c) * lb
    denominator = la * lb * lc + dots + np.einsum("ij,ij->i", b, c) * la
    return 2.0 * np.arctan2(numerator, denominator)


def _cut(
    vertices: FloatArray, faces: IntArray, normal: tuple[float, float, float]
) -> tuple[FloatArray, IntArray]:
    """The part of a triangle soup on the side n · v ≥ 0 of a plane through the shoulder."""
    if len(faces) == 0:
        return vertices, faces
    kept = trimesh.intersections.slice_faces_plane(vertices, faces, normal, (0.0, 0.0, 0.0))
    return np.asarray(kept[0], dtype=np.float64), np.asarray(kept[1], dtype=np.int64)


def covered_patch(directions: FloatArray) -> tuple[FloatArray, IntArray]:
    """Faces of the convex hull of the shoulder and the unit ``directions`` that do not touch the
    shoulder, i.e. the patch of the sphere they span (empty when they span no area)."""
    empty = np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    if len(directions) < 3 or np.linalg.matrix_rank(directions, tol=1e-6) < 3:
        return empty  # all in one plane through the shoulder: a curve, no area
    try:
        hull = trimesh.convex.convex_hull(np.vstack((np.zeros((1, 3)), directions)), repair=False)
    except (QhullError, ValueError):
        return empty
    vertices = np.asarray(hull.vertices, dtype=np.float64)
    at_shoulder = np.linalg.norm(vertices, axis=1) < 1e-6
    faces = np.asarray(hull.faces, dtype=np.int64)
    faces = faces[~at_shoulder[faces].any(axis=1)]
    used, faces = np.unique(faces, return_inverse=True)
    return vertices[used], faces.reshape(-1, 3).astype(np.int64)


def workspace_from_points(points: FloatArray, side: str, arm_length: float = 1.0) -> Workspace:
    """Workspace of hand positions (N, 3) relative to the shoulder, in arm lengths, axes X
    anterior, Y superior, Z lateral (see the module doc)."""
    points = np.asarray(points, dtype=np.float64)
    points = points[np.all(np.isfinite(points), axis=1)]
    directions = unit(points[np.linalg.norm(points, axis=1) > 1e-6])
    vertices, faces = covered_patch(directions)
    front_v, front_f = _cut(vertices, faces, (1.0, 0.0, 0.0))
    quadrants = {}
    for name, (up, lateral) in QUADRANTS.items():
        half_v, half_f = _cut(front_v, front_f, (0.0, up, 0.0))
        v, f = _cut(half_v, half_f, (0.0, 0.0, lateral))
        quadrants[name] = round(float(solid_angles(v, f).sum() / HEMISPHERE_SR), 4)
    total = round(float(solid_angles(front_v, front_f).sum() / HEMISPHERE_SR), 4)
    return Workspace(side, total, quadrants, vertices, faces, float(arm_length))


def hand_paths(
    motion: Motion, kin: Kinematics | None = None, body: Body | None = None
) -> dict[str, tuple[FloatArray, float]]:
    """Per side: the wrist relative to the shoulder in thorax axes (Z lateral), in arm lengths,
    (F, 3), and the arm's length in file units; ``kin`` / ``body`` as for `geometry`."""
    body = find_body(motion.skeleton) if body is None else body
    kin = kinematics(motion) if kin is None else kin
    thorax = geometry(motion, kin=kin, body=body).thorax
    if thorax is None:
        return {}
    pos = kin.positions
    out = {}
    for side in SIDES:
        try:
            s, e, w = (body.joints[f"{j}_{side}"] for j in ("shoulder", "elbow", "wrist"))
        except KeyError:
            continue
        segments = np.linalg.norm(pos[:, [e, w]] - pos[:, [s, e]], axis=-1).sum(axis=1)
        length = float(np.median(segments))
        local = np.einsum("fij,fi->fj", thorax, pos[:, w] - pos[:, s])
        local[:, 2] *= SIDE_SIGN[side]
        out[side] = (local / length, length)
    return out


def reachable_workspace(
    motion: Motion,
    start: int | None = None,
    end: int | None = None,
    *,
    kin: Kinematics | None = None,
    body: Body | None = None,
) -> dict[str, Workspace]:
    """The workspace of each hand the skeleton has, over frames ``start..end`` (inclusive);
    ``kin`` / ``body``: the motion's kinematics and body parts when already computed."""
    stop = None if end is None else end + 1
    return {
        side: workspace_from_points(path[start:stop], side, length)
        for side, (path, length) in hand_paths(motion, kin, body).items()
    }
