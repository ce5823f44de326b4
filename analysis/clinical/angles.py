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
- ``shoulder_elevation``: the upper arm in the thorax frame as ISB's globe (Wu et al. 2005,
  Y-X-Y): its elevation, the angle between the upper arm and the trunk's downward axis, whatever
  the plane of elevation (0 out to the side, 90 forward, −90 backward; `shoulder_globe`).
- ``shoulder_flexion`` / ``shoulder_abduction``: as a goniometer reads them, which lines up its
  arms with the trunk and the upper arm and so reads the elevation. Abduction is the elevation
  while the arm rises within 45° of the frontal plane (the scapular plane included), fading to 0
  at the sagittal plane; flexion the elevation within 45° of the sagittal plane forward, fading
  to 0 at the frontal plane; below shoulder height an arm behind the frontal plane reads
  extension (negative flexion). Within 15° of straight up the plane of elevation is undefined,
  and both read the elevation there. An arm raised overhead thus reads its elevation, not a
  share of it; an arm straight forward is flexion 90°, abduction 0°; a diagonal arm at 45° reads
  its elevation in both.
- ``knee_flexion`` / ``elbow_flexion``: the angle between the two segments' long axes (0 when
  straight; hinge joints, hyperextension is not told apart).
- ``ankle_dorsiflexion``: the change of the angle between shank and foot from the rest pose's,
  the one zero taken from the rig: without a heel joint the sole's direction is unknown, and rigs
  stand flat-footed in their rest pose whatever they do with the arms (so it is left out where
  the rest shank does not hang within 45° of the vertical).
"""

from __future__ import annotations

import numpy as np

from analysis.bvh import Motion
from analysis.clinical.body import (
    MAX_REST_TILT,
    SIDE_SIGN,
    SIDES,
    FloatArray,
    Geometry,
    geometry,
    unit,
)
from analysis.clinical.measured import Measured, missing_notes, within_limits
from analysis.clinical.results import AngleRange

BILATERAL = (
    "knee_flexion", "hip_flexion", "hip_abduction", "ankle_dorsiflexion",
    "shoulder_flexion", "shoulder_abduction", "shoulder_elevation", "elbow_flexion",
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


def trunk_angles(pelvis: FloatArray, thorax: FloatArray, up: FloatArray) -> dict[str, FloatArray]:
    forward = unit(pelvis[..., 0] - np.outer(pelvis[..., 0] @ up, up))
    right = np.cross(forward, up)
    axis = thorax[..., 1]
    return {
        "trunk_flexion": np.degrees(np.arctan2(np.sum(axis * forward, -1), axis @ up)),
        "trunk_lateral_flexion": np.degrees(np.arcsin(np.clip(np.sum(axis * right, -1), -1, 1))),
    }


def hip_angles(pelvis: FloatArray, thigh: FloatArray, side: str) -> dict[str, FloatArray]:
    x, y, z = _in_frame(pelvis, thigh).T
    return {
        f"hip_flexion_{side}": np.degrees(np.arctan2(x, -y)),
        f"hip_abduction_{side}": np.degrees(np.arcsin(np.clip(SIDE_SIGN[side] * z, -1, 1))),
    }


OVERHEAD = (165.0, 180.0)  # elevations over which the plane of elevation fades out


def shoulder_globe(thorax: FloatArray, arm: FloatArray, side: str) -> tuple[FloatArray, FloatArray]:
    """The upper arm's elevation from hanging (0..180°) and its plane of elevation (degrees
    from the frontal plane: 0 out to the side, 90 forward, −90 backward, ±180 across the body),
    ISB's first two globe angles of the humerus in the thorax frame."""
    x, y, z = _in_frame(thorax, arm).T
    elevation = np.degrees(np.arccos(np.clip(-y, -1.0, 1.0)))
    return elevation, np.degrees(np.arctan2(x, SIDE_SIGN[side] * z))


def _share(plane: FloatArray, centre: float) -> FloatArray:
    """1 within 45° of the centre plane, fading linearly to 0 at 90° from it."""
    off = np.abs((plane - centre + 180.0) % 360.0 - 180.0)
    return np.clip((90.0 - off) / 45.0, 0.0, 1.0)


def shoulder_angles(thorax: FloatArray, arm: FloatArray, side: str) -> dict[str, FloatArray]:
    elevation, plane = shoulder_globe(thorax, arm, side)
    top = np.clip((elevation - OVERHEAD[0]) / (OVERHEAD[1] - OVERHEAD[0]), 0.0, 1.0)
    forward, backward = _share(plane, 90.0), _share(plane, -90.0)
    low = elevation <= 90.0  # below the shoulder: an arm behind the trunk is extension
    flexion = np.where(low, forward - backward, np.maximum(np.maximum(forward, backward), top))
    return {
        f"shoulder_flexion_{side}": elevation * flexion,
        f"shoulder_abduction_{side}": elevation * np.maximum(_share(plane, 0.0), top),
        f"shoulder_elevation_{side}": elevation,
    }


def _stands_on(geo: Geometry, shank: str) -> bool:
    """Whether the rest pose stands on this leg (its shank hangs within 45° of the vertical),
    so that its foot gives the ankle's zero."""
    return geo.upright and bool(-geo.rest_axes[shank] @ geo.up > MAX_REST_TILT)


def _limb_angles(geo: Geometry, side: str) -> dict[str, FloatArray]:
    axes, out = geo.axes, {}
    pairs = {"knee_flexion": ("thigh", "shank"), "elbow_flexion": ("upper_arm", "forearm")}
    for name, (a, b) in pairs.items():
        if f"{a}_{side}" in axes and f"{b}_{side}" in axes:
            out[f"{name}_{side}"] = _between(axes[f"{a}_{side}"], axes[f"{b}_{side}"])
    shank, foot = f"shank_{side}", f"foot_{side}"
    if shank in axes and foot in axes and _stands_on(geo, shank):
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
        out.update(trunk_angles(geo.pelvis, geo.thorax, geo.up))
    return {name: out[name] for name in ANGLE_NAMES if name in out}


def measure(motion: Motion, method: str = "orientation") -> Measured:
    """The angles this recording measures (`angle_series`) and, for every other angle of
    `ANGLE_NAMES`, why not (``clinical_notes``: the skeleton lacks a segment, or the readings
    leave the body's physiological limits; `analysis.clinical.measured`)."""
    geo = geometry(motion, method)
    raw = angles_of(geo)
    measured = within_limits(raw)
    notes = {**missing_notes(geo, ANGLE_NAMES, raw), **measured.notes}
    return Measured(measured.series, {name: notes[name] for name in ANGLE_NAMES if name in notes})


def angle_series(
    motion: Motion, method: str = "orientation", within_body_limits: bool = True
) -> dict[str, FloatArray]:
    """Anatomical angles of every frame: {name: (F,) degrees}, only those the recording
    measures: the skeleton gives them and they stay within the body's limits (the few frames
    beyond are NaN; `measure` says why an angle is missing). ``within_body_limits=False``: every
    angle the skeleton gives, as read.

    ``method="orientation"`` (default) reads the segments' global rotations; ``"positions"``
    only the joints' world positions (the cross-check). Frames where a segment has no length
    give NaN.
    """
    if not within_body_limits:
        return angles_of(geometry(motion, method))
    return measure(motion, method).series


def angle_ranges(
    series: dict[str, FloatArray], start: int | None = None, end: int | None = None
) -> dict[str, AngleRange]:
    """Min and max of each angle over frames ``start..end`` (both included, as in a
    repetition's frames; None: the recording's first / last frame), rounded to 0.01°.
    Angles with no finite value there are left out."""
    stop = None if end is None else end + 1
    out = {}
    for name, values in series.items():
        part = np.asarray(values[start:stop], dtype=np.float64)
        part = part[np.isfinite(part)]
        if part.size:
            out[name] = AngleRange(round(float(part.min()), 2), round(float(part.max()), 2))
    return out


def clinical_angles(motion: Motion) -> dict[str, AngleRange]:
    """The ``clinical_angles`` field of a result: each measured angle's range over the whole
    recording (`measure` gives the ``clinical_notes`` of the others)."""
    return angle_ranges(angle_series(motion))
