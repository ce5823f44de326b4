"""Anatomical joint angles in degrees, per frame, and their ranges per recording or repetition.

Convention (docs/sections/clinical.md has the figures): 0 in the anatomical standing pose,
flexion, abduction and dorsiflexion positive, their opposites (extension, adduction, plantar
flexion) negative. Segment frames are ISB-style (X anterior, Y superior, Z right; see
`analysis.clinical.body`). Axial rotations are not reported: Kinect-class rigs do not measure a
bone's roll, so every angle here depends only on long axes and the pelvis and thorax frames.

- ``trunk_flexion`` / ``trunk_lateral_flexion``: the thorax's long axis against the vertical,
  Cardan angles in the pelvis's heading (forward lean positive; lean to the right positive).
- ``hip_flexion`` / ``hip_abduction``: the thigh in the pelvis frame, ISB hip joint coordinate
  system (Cardan Z-X-Y: flexion about the pelvis's mediolateral axis, then ab/adduction).
- ``shoulder_flexion`` / ``shoulder_abduction``: the upper arm in the thorax frame, as the
  components of its attitude (rotation) vector from hanging down (Woltring 1994): elevation
  times the plane's share, so each is the goniometer's angle for a movement in its own plane
  (flexion in the sagittal, abduction in the frontal plane) with no gimbal lock at 90°, where
  Cardan angles of the shoulder fail. An arm straight forward is flexion 90°, abduction 0°. The
  one singular direction is straight up (the plane is undefined there): an arm tipping over the
  top medially reads negative abduction, which Kinect glitches overhead do on UI-PRMD squats.
- ``knee_flexion`` / ``elbow_flexion``: the angle between the two segments' long axes (0 when
  straight; hinge joints, hyperextension is not told apart).
- ``ankle_dorsiflexion``: the change of the angle between shank and foot from the rest pose's,
  the one zero taken from the rig: without a heel joint the sole's direction is unknown, and rigs
  stand flat-footed in their rest pose whatever they do with the arms (so it is left out where
  the rest shank does not hang within 45° of the vertical).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from analysis.bvh import Motion
from analysis.clinical.body import (
    MAX_REST_TILT,
    SIDE_SIGN,
    SIDES,
    UP,
    FloatArray,
    Geometry,
    geometry,
    unit,
)

if TYPE_CHECKING:
    from analysis.pipeline.results import AngleRange

BILATERAL = (
    "knee_flexion", "hip_flexion", "hip_abduction", "ankle_dorsiflexion",
    "shoulder_flexion", "shoulder_abduction", "elbow_flexion",
)  # fmt: skip
ANGLE_NAMES: tuple[str, ...] = (
    *(f"{name}_{side}" for name in BILATERAL for side in SIDES),
    "trunk_flexion",
    "trunk_lateral_flexion",
)


def _between(u: FloatArray, v: FloatArray) -> FloatArray:
    """Angle between unit vectors, degrees: (F,)."""
    return np.degrees(np.arccos(np.clip(np.sum(u * v, axis=-1), -1.0, 1.0)))


def _in_frame(frame: FloatArray, v: FloatArray) -> FloatArray:
    """Components of world vectors v (F, 3) along the frame's axes (F, 3, 3): (F, 3)."""
    return np.einsum("fij,fi->fj", frame, v)


def trunk_angles(pelvis: FloatArray, thorax: FloatArray) -> dict[str, FloatArray]:
    forward = unit(pelvis[..., 0] - np.outer(pelvis[..., 0] @ UP, UP))
    right = np.cross(forward, UP)
    axis = thorax[..., 1]
    return {
        "trunk_flexion": np.degrees(np.arctan2(np.sum(axis * forward, -1), axis @ UP)),
        "trunk_lateral_flexion": np.degrees(np.arcsin(np.clip(np.sum(axis * right, -1), -1, 1))),
    }


def hip_angles(pelvis: FloatArray, thigh: FloatArray, side: str) -> dict[str, FloatArray]:
    x, y, z = _in_frame(pelvis, thigh).T
    return {
        f"hip_flexion_{side}": np.degrees(np.arctan2(x, -y)),
        f"hip_abduction_{side}": np.degrees(np.arcsin(np.clip(SIDE_SIGN[side] * z, -1, 1))),
    }


def shoulder_angles(thorax: FloatArray, arm: FloatArray, side: str) -> dict[str, FloatArray]:
    x, y, z = _in_frame(thorax, arm).T
    elevation = np.degrees(np.arccos(np.clip(-y, -1.0, 1.0)))
    across = np.hypot(x, z)  # sine of the elevation: the attitude vector's direction is (−z, 0, x)
    with np.errstate(invalid="ignore", divide="ignore"):
        share_x, share_z = (
            np.where(across > 1e-9, x / across, 0.0),
            np.where(across > 1e-9, z / across, 0.0),
        )
    return {
        f"shoulder_flexion_{side}": elevation * share_x,
        f"shoulder_abduction_{side}": elevation * SIDE_SIGN[side] * share_z,
    }


def _limb_angles(geo: Geometry, side: str) -> dict[str, FloatArray]:
    axes, out = geo.axes, {}
    pairs = {"knee_flexion": ("thigh", "shank"), "elbow_flexion": ("upper_arm", "forearm")}
    for name, (a, b) in pairs.items():
        if f"{a}_{side}" in axes and f"{b}_{side}" in axes:
            out[f"{name}_{side}"] = _between(axes[f"{a}_{side}"], axes[f"{b}_{side}"])
    shank, foot = f"shank_{side}", f"foot_{side}"
    if shank in axes and foot in axes and -geo.rest_axes[shank] @ UP > MAX_REST_TILT:
        neutral = _between(-geo.rest_axes[shank], geo.rest_axes[foot])
        out[f"ankle_dorsiflexion_{side}"] = neutral - _between(-axes[shank], axes[foot])
    return out


def angles_of(geo: Geometry) -> dict[str, FloatArray]:
    """Every angle the geometry gives, degrees per frame, in `ANGLE_NAMES` order."""
    out: dict[str, FloatArray] = {}
    for side in SIDES:
        out.update(_limb_angles(geo, side))
        if geo.pelvis is not None and f"thigh_{side}" in geo.axes:
            out.update(hip_angles(geo.pelvis, geo.axes[f"thigh_{side}"], side))
        if geo.thorax is not None and f"upper_arm_{side}" in geo.axes:
            out.update(shoulder_angles(geo.thorax, geo.axes[f"upper_arm_{side}"], side))
    if geo.pelvis is not None and geo.thorax is not None:
        out.update(trunk_angles(geo.pelvis, geo.thorax))
    return {name: out[name] for name in ANGLE_NAMES if name in out}


def angle_series(motion: Motion, method: str = "orientation") -> dict[str, FloatArray]:
    """Anatomical angles of every frame: {name: (F,) degrees}, only those the skeleton gives.

    ``method="orientation"`` (default) reads the segments' global rotations; ``"positions"``
    only the joints' world positions (the cross-check). Frames where a segment has no length
    give NaN.
    """
    return angles_of(geometry(motion, method))


def angle_ranges(
    series: dict[str, FloatArray], start: int | None = None, end: int | None = None
) -> dict[str, AngleRange]:
    """Min and max of each angle over frames ``start..end`` (both included, as in a
    repetition's frames; None: the recording's first / last frame), rounded to 0.01°.
    Angles with no finite value there are left out."""
    from analysis.pipeline.results import AngleRange  # lazily: the pipeline imports this module

    stop = None if end is None else end + 1
    out = {}
    for name, values in series.items():
        part = np.asarray(values[start:stop], dtype=np.float64)
        part = part[np.isfinite(part)]
        if part.size:
            out[name] = AngleRange(round(float(part.min()), 2), round(float(part.max()), 2))
    return out


def clinical_angles(motion: Motion) -> dict[str, AngleRange]:
    """The ``clinical_angles`` field of a result: each angle's range over the whole recording."""
    return angle_ranges(angle_series(motion))
