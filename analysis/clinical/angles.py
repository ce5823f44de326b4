"""Anatomical joint angles in degrees, per frame, and their ranges per recording or repetition.

Convention (docs/sections/clinical.md has the figures): 0 in the anatomical standing pose,
flexion, abduction and dorsiflexion positive, their opposites (extension, adduction, plantar
flexion) negative. Segment frames are ISB-style (X anterior, Y superior, Z right; see
`analysis.clinical.body`). No angle reads a bone's roll about itself (Kinect-class rigs do not
measure it): every angle here depends only on long axes and the pelvis and thorax frames; the
upper arm's axial rotation is read from where the bent forearm points.

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
- ``shoulder_plane_of_elevation``: the globe's first angle, the direction the arm is raised in
  (0 out to the side, 90 straight forward, negative behind the side, over 90 across the body);
  only where the arm is raised between `PLANE_DEFINED` degrees (hanging or straight up, the
  direction is undefined).
- ``shoulder_rotation``: the upper arm's axial rotation, internal (the forearm turning toward
  the belly) positive, 0 with the forearm pointing forward from an arm hanging at the side. Read
  from the forearm's direction about the upper arm's axis, against the thorax's forward axis
  carried along the shortest turn from hanging to the arm's direction (so 0 is also the forearm
  pointing forward with the arm raised to the side, and up with the arm raised forward); only
  where the elbow is bent between `ROTATION_ELBOW_DEG`'s bounds and the arm is below
  `PLANE_DEFINED`'s upper end (a straight forearm, or one folded back onto the upper arm, has no
  direction about it).
- ``knee_flexion`` / ``elbow_flexion``: the angle between the two segments' long axes (0 when
  straight; hinge joints, hyperextension is not told apart).
- ``ankle_dorsiflexion``: the change of the angle between shank and foot from its value when
  the person stands (`ankle_zero`): without a heel joint the sole's direction is unknown, and a
  rig's foot joints sit anywhere along the foot (a Kinect's ankle → foot line points 15–45°
  down in a standing person, yet 0° in its rest pose), so the zero comes from the recording's
  own standing frames (knee straight, shank upright over the foot: `standing_frames`); only
  where the person never stands so, from the rest pose when it stands (else not measured).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion
from analysis.clinical.body import (
    MAX_REST_TILT,
    SIDE_SIGN,
    SIDES,
    Body,
    FloatArray,
    Geometry,
    geometry,
    unit,
)
from analysis.clinical.measured import (
    NOT_MEASURABLE,
    Measured,
    missing_notes,
    within_limits,
    without_lost_frames,
)
from analysis.clinical.results import AngleRange
from analysis.kinematics import Kinematics

BILATERAL = (
    "knee_flexion", "hip_flexion", "hip_abduction", "ankle_dorsiflexion",
    "shoulder_flexion", "shoulder_abduction", "shoulder_elevation",
    "shoulder_plane_of_elevation", "shoulder_rotation", "elbow_flexion",
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


PLANE_DEFINED = (30.0, 150.0)  # elevations between which the arm's direction is defined
# a straighter forearm, or one folded back onto the upper arm, gives no direction about it
ROTATION_ELBOW_DEG = (30.0, 150.0)
DEFINED_SHARE = 0.1  # defined in fewer of the frames: the recording does not measure the angle


def _carried(v: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Vectors v (F, 3) turned by the shortest rotation taking unit a onto unit b (Rodrigues'
    formula with c = a × b; NaN where a and b are opposite)."""
    c = np.cross(a, b)
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = 1.0 / (1.0 + np.sum(a * b, axis=-1, keepdims=True))
    return v + np.cross(c, v) + scale * np.cross(c, np.cross(c, v))


def _mostly_undefined(values: FloatArray) -> FloatArray:
    """All NaN when the angle is defined in fewer than `DEFINED_SHARE` of the frames."""
    return values if np.isfinite(values).mean() >= DEFINED_SHARE else np.full_like(values, np.nan)


def shoulder_rotation(
    thorax: FloatArray, arm: FloatArray, forearm: FloatArray, side: str
) -> FloatArray:
    """Axial rotation of the upper arm, internal positive (module docstring), degrees per
    frame; NaN where the elbow is nearly straight or the arm near straight up."""
    return _mostly_undefined(_rotation_read(thorax, arm, forearm, side))


def _rotation_read(
    thorax: FloatArray, arm: FloatArray, forearm: FloatArray, side: str
) -> FloatArray:
    """`shoulder_rotation` of each frame alone (before the share of defined frames is
    checked)."""
    reference = _carried(thorax[..., 0], -thorax[..., 1], arm)
    outward = np.cross(arm, reference)  # to the body's right for either arm hanging
    turned = np.degrees(
        np.arctan2(
            -SIDE_SIGN[side] * np.sum(forearm * outward, -1), np.sum(forearm * reference, -1)
        )
    )
    elevation, _ = shoulder_globe(thorax, arm, side)
    elbow = _between(arm, forearm)
    bent = (elbow >= ROTATION_ELBOW_DEG[0]) & (elbow <= ROTATION_ELBOW_DEG[1])
    defined = bent & (elevation <= PLANE_DEFINED[1])
    return np.where(defined, turned, np.nan)


def plane_of_elevation(thorax: FloatArray, arm: FloatArray, side: str) -> FloatArray:
    """The direction the arm is raised in (module docstring), degrees per frame; NaN where
    the arm hangs or points nearly straight up."""
    return _mostly_undefined(_plane_read(thorax, arm, side))


def _plane_read(thorax: FloatArray, arm: FloatArray, side: str) -> FloatArray:
    """`plane_of_elevation` of each frame alone (before the share of defined frames is
    checked)."""
    elevation, plane = shoulder_globe(thorax, arm, side)
    defined = (elevation >= PLANE_DEFINED[0]) & (elevation <= PLANE_DEFINED[1])
    # across the body reads past 90 (not −180..−90): the arm sweeps on from forward
    plane = np.where(plane < -135.0, plane + 360.0, plane)
    return np.where(defined, plane, np.nan)


def _stands_on(geo: Geometry, shank: str) -> bool:
    """Whether the rest pose stands on this leg (its shank hangs within 45° of the vertical),
    so that its foot gives the ankle's zero."""
    return geo.upright and bool(-geo.rest_axes[shank] @ geo.up > MAX_REST_TILT)


# Standing on a leg: the knee within STANDING_KNEE_DEG of straight and the shank within
# STANDING_LEAN_DEG of upright over the foot (forward or backward; leaning sideways, as with the
# feet set wide, leaves the ankle's bend unchanged); at least MIN_STANDING such frames (a third
# of a second at 30 fps) to take the ankle's zero from.
STANDING_KNEE_DEG, STANDING_LEAN_DEG, MIN_STANDING = 15.0, 15.0, 10
STEADY_FOOT_DEG = 20.0  # the standing foot's 10–90 % spread: beyond it, no zero


def standing_frames(geo: Geometry, side: str) -> FloatArray:
    """Per frame, whether the person stands on this leg (boolean (F,); all False without the
    thigh, shank and foot)."""
    names = [f"{p}_{side}" for p in ("thigh", "shank", "foot")]
    if any(name not in geo.axes for name in names):
        return np.zeros(len(next(iter(geo.axes.values()), ())), dtype=bool)
    thigh, shank, foot = (geo.axes[name] for name in names)
    ahead = unit(foot - np.outer(foot @ geo.up, geo.up))  # the way the foot points, level
    lean = np.degrees(np.arcsin(np.clip(np.sum(-shank * ahead, axis=-1), -1.0, 1.0)))
    with np.errstate(invalid="ignore"):
        return (_between(thigh, shank) < STANDING_KNEE_DEG) & (np.abs(lean) < STANDING_LEAN_DEG)


def ankle_zero(geo: Geometry, side: str) -> tuple[float | None, str]:
    """The shank–foot angle (degrees) of this recording's person standing flat-footed (the
    median over the standing frames; without enough of them, the rest pose's where the rest
    pose stands), or None and why not: no standing, or a foot whose direction jumps by more
    than `STEADY_FOOT_DEG` while the person stands (a Kinect foot flipping between two readings:
    no zero is right then)."""
    shank, foot = geo.axes[f"shank_{side}"], geo.axes[f"foot_{side}"]
    standing = standing_frames(geo, side)
    if standing.sum() >= MIN_STANDING:
        bends = _between(-shank[standing], foot[standing])
        low, high = np.nanpercentile(bends, [10.0, 90.0])
        if high - low > STEADY_FOOT_DEG:
            return None, (
                f"the foot's direction jumps by {high - low:.0f}° while the person stands still, "
                "so its neutral position cannot be told"
            )
        return float(np.nanmedian(bends)), ""
    if _stands_on(geo, f"shank_{side}"):
        rest = _between(-geo.rest_axes[f"shank_{side}"], geo.rest_axes[f"foot_{side}"])
        return float(rest), ""
    return None, "the person never stands with a straight knee in it to measure the foot from"


def _limb_angles(axes: dict[str, FloatArray], side: str) -> dict[str, FloatArray]:
    out = {}
    pairs = {"knee_flexion": ("thigh", "shank"), "elbow_flexion": ("upper_arm", "forearm")}
    for name, (a, b) in pairs.items():
        if f"{a}_{side}" in axes and f"{b}_{side}" in axes:
            out[f"{name}_{side}"] = _between(axes[f"{a}_{side}"], axes[f"{b}_{side}"])
    shank, foot = f"shank_{side}", f"foot_{side}"
    if shank in axes and foot in axes:  # the shank–foot angle, before the ankle's zero
        out[f"{ANKLE_BEND}{side}"] = _between(-axes[shank], axes[foot])
    return out


def _shoulder(thorax: FloatArray, axes: dict[str, FloatArray], side: str) -> dict[str, FloatArray]:
    arm = axes[f"upper_arm_{side}"]
    out = shoulder_angles(thorax, arm, side)
    out[f"{READ}shoulder_plane_of_elevation_{side}"] = _plane_read(thorax, arm, side)
    if f"forearm_{side}" in axes:
        out[f"{READ}shoulder_rotation_{side}"] = _rotation_read(
            thorax, arm, axes[f"forearm_{side}"], side
        )
    return out


ANKLE_BEND = "ankle_bend_"  # `frame_angles`' shank–foot angle, "ankle_bend_left"
READ = "read:"  # `frame_angles`' angles before the share of frames defining them is checked


def frame_angles(geo: Geometry) -> dict[str, FloatArray]:
    """The angles of each frame that read that frame alone and not the take's vertical
    (degrees per frame): the limbs, hips and shoulders, the shoulder's plane of elevation and
    rotation as read (`READ`), the ankle's shank–foot angle before its zero (`ANKLE_BEND`).
    `take_angles` turns them into the recording's angles; a live session keeps them frame by
    frame, as the frames arrive, and runs only `take_angles` over every frame so far."""
    out: dict[str, FloatArray] = {}
    for side in SIDES:
        out.update(_limb_angles(geo.axes, side))
        if geo.pelvis is not None and f"thigh_{side}" in geo.axes:
            out.update(hip_angles(geo.pelvis, geo.axes[f"thigh_{side}"], side))
        if geo.thorax is not None and f"upper_arm_{side}" in geo.axes:
            out.update(_shoulder(geo.thorax, geo.axes, side))
    return out


def take_angles(geo: Geometry, each: dict[str, FloatArray]) -> dict[str, FloatArray]:
    """Every angle the geometry gives (`angles_of`) from its frames' `frame_angles` (``each``,
    of the same frames): the steps that read the whole take run here (the share of frames a
    shoulder angle is defined in, the ankle's zero from the standing frames, the trunk against
    the take's vertical)."""
    out = {k: v for k, v in each.items() if not k.startswith((READ, ANKLE_BEND))}
    for name, values in each.items():
        if name.startswith(READ):
            out[name.removeprefix(READ)] = _mostly_undefined(values)
    for side in SIDES:
        bend = each.get(f"{ANKLE_BEND}{side}")
        neutral = ankle_zero(geo, side)[0] if bend is not None else None
        if bend is not None and neutral is not None:
            out[f"ankle_dorsiflexion_{side}"] = neutral - bend
    if geo.pelvis is not None and geo.thorax is not None:
        out.update(trunk_angles(geo.pelvis, geo.thorax, geo.up))
    return {name: out[name] for name in ANGLE_NAMES if name in out}


def angles_of(geo: Geometry) -> dict[str, FloatArray]:
    """Every angle the geometry gives, degrees per frame, in `ANGLE_NAMES` order."""
    return take_angles(geo, frame_angles(geo))


def _ankle_notes(geo: Geometry, given: dict[str, FloatArray]) -> dict[str, str]:
    """Why an ankle the skeleton has the segments for is not measured (`ankle_zero`)."""
    out = {}
    for side in SIDES:
        name = f"ankle_dorsiflexion_{side}"
        if name not in given and {f"shank_{side}", f"foot_{side}"} <= set(geo.axes):
            out[name] = f"{NOT_MEASURABLE}: {ankle_zero(geo, side)[1]}"
    return out


def measure(
    motion: Motion,
    method: str = "orientation",
    *,
    kin: Kinematics | None = None,
    body: Body | None = None,
    lost: Mapping[str, npt.NDArray[np.bool_]] | None = None,
) -> Measured:
    """The angles this recording measures (`angle_series`) and, for every other angle of
    `ANGLE_NAMES`, why not (``clinical_notes``: the skeleton lacks a segment, or the readings
    leave the body's physiological limits; `analysis.clinical.measured`); ``kin`` / ``body``:
    the motion's kinematics and body parts when already computed (`geometry`); ``lost``: per
    joint the capture lost ({"left_shoulder": (F,) bool}), the frames left out of its angles
    (`analysis.clinical.measured.without_lost_frames`)."""
    geo = geometry(motion, method, kin=kin, body=body)
    raw = angles_of(geo)
    measured = within_limits(without_lost_frames(raw, lost) if lost else raw)
    notes = {**missing_notes(geo, ANGLE_NAMES, raw), **_ankle_notes(geo, raw), **measured.notes}
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
