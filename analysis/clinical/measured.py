"""Which angles a recording measures, and why the others are not measurements.

An angle is a measurement only where the skeleton has the segments it needs and the values stay
within what a body can reach (`analysis.clinical.norms.LIMITS`). A reading beyond those limits
is the capture losing track of a joint (a Kinect foot, an arm seen edge-on), not a movement:

- a few such frames (at most `MAX_BEYOND_SHARE` of the tracked ones) are left out of the
  angle's series (NaN), so they widen no range;
- more than that, and the whole angle is not measurable in this recording: it is left out, and
  `clinical_notes` says why in plain words (as does every angle the skeleton cannot give).

A foot's angle whose frame-to-frame noise alone adds more to its range than a correction's
tolerance (`analysis.assessment.compensations.jitter` against `NOISY_DEG`: a Kinect foot
flipping by 40° between frames) is "not measurable reliably in this recording" with that
reason: no range or correction comes from it.

The interface contract's ``clinical_angles`` / ``clinical_notes``; docs/sections/clinical.md.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from analysis.assessment.compensations import NOT_RELIABLE, jitter
from analysis.assessment.findings import TOLERANCE_DEG
from analysis.clinical.body import SIDES, FloatArray, Geometry
from analysis.clinical.norms import limits_for

MAX_BEYOND_SHARE = 0.05  # of the tracked frames: more read beyond the limits, no measurement
NOT_MEASURABLE = "not measurable in this recording"
# the angles whose noise is checked (Kinect-class feet; other segments' jumps are movement)
NOISE_CHECKED = ("ankle_dorsiflexion",)
NOISY_DEG = TOLERANCE_DEG  # the noise alone adds more to a range than a correction tolerates
# angle (without side) -> the segments it needs: limb axes by name, "pelvis" / "thorax" frames
NEEDS = {
    "knee_flexion": ("thigh", "shank"),
    "hip_flexion": ("pelvis", "thigh"),
    "hip_abduction": ("pelvis", "thigh"),
    "ankle_dorsiflexion": ("shank", "foot"),
    "shoulder_flexion": ("thorax", "upper_arm"),
    "shoulder_abduction": ("thorax", "upper_arm"),
    "shoulder_elevation": ("thorax", "upper_arm"),
    "shoulder_plane_of_elevation": ("thorax", "upper_arm"),
    "shoulder_rotation": ("thorax", "upper_arm", "forearm"),
    "elbow_flexion": ("upper_arm", "forearm"),
    "trunk_flexion": ("pelvis", "thorax"),
    "trunk_lateral_flexion": ("pelvis", "thorax"),
}
# angles defined only in some positions: why one defined in too few frames is no measurement
UNDEFINED_WHY = {
    "shoulder_plane_of_elevation": "the arm was not raised far enough from the side (30°) for "
    "the direction it rises in to be seen",
    "shoulder_rotation": "the elbow stayed nearly straight, so the upper arm's turn about itself "
    "cannot be seen (it is read from where the bent forearm points)",
}
SEGMENT_WORDS = {
    "thigh": "thigh", "shank": "lower leg", "foot": "foot", "upper_arm": "upper arm",
    "forearm": "forearm", "pelvis": "pelvis", "thorax": "upper back and shoulders",
}  # fmt: skip


@dataclass(frozen=True)
class Measured:
    """Per-frame degrees of the angles this recording measures, and a plain-words reason for
    each angle it does not (``{"knee_flexion_left": "not measurable in this recording: …"}``)."""

    series: dict[str, FloatArray]
    notes: dict[str, str] = field(default_factory=dict)


def _degrees(value: float) -> str:
    return f"{value:.0f}°".replace("-", "−")


def beyond_note(values: FloatArray, low: float, high: float, share: float) -> str:
    """Why an angle whose readings leave the body's limits is no measurement."""
    worst = float(values[np.argmax(np.maximum(low - values, values - high))])
    return (
        f"{NOT_MEASURABLE}: {round(100 * share)} % of the frames read beyond what a body can "
        f"reach ({_degrees(low)} to {_degrees(high)}), up to {_degrees(worst)}; the capture "
        "lost track of this joint"
    )


def within_limits(series: Mapping[str, FloatArray]) -> Measured:
    """The series with frames beyond the physiological limits left out (NaN), and the angles
    with too many of them (or none tracked) moved to the notes."""
    kept: dict[str, FloatArray] = {}
    notes: dict[str, str] = {}
    for name, read in series.items():
        low, high = limits_for(name)
        values = np.asarray(read, dtype=np.float64)
        tracked = np.isfinite(values)
        beyond = tracked & ((values < low) | (values > high))
        if not tracked.any():
            why = UNDEFINED_WHY.get(_base(name), "the joint was not tracked in any frame")
            notes[name] = f"{NOT_MEASURABLE}: {why}"
        elif beyond.sum() > MAX_BEYOND_SHARE * tracked.sum():
            notes[name] = beyond_note(values[beyond], low, high, beyond.sum() / tracked.sum())
        elif _base(name) in NOISE_CHECKED and (noise := jitter(values[~beyond])) > NOISY_DEG:
            notes[name] = (
                f"{NOT_RELIABLE}: it jumps by about {noise:.0f}° from one frame to the next, "
                f"more than the {NOISY_DEG:.0f}° a correction would be about"
            )
        else:
            kept[name] = np.where(beyond, np.nan, values)
    return Measured(kept, notes)


def without_lost_frames(
    series: Mapping[str, FloatArray], lost: Mapping[str, npt.NDArray[np.bool_]]
) -> dict[str, FloatArray]:
    """The series with the frames where the capture lost a joint left out (NaN) of that joint's
    angles: ``lost`` {"left_shoulder": (F,) bool} blanks every ``shoulder_…_left`` angle there
    (the upper arm was pointed from where the recorder put the lost shoulder)."""
    out = dict(series)
    for joint, frames in lost.items():
        side, _, part = joint.partition("_")
        for name in series:
            if name.startswith(f"{part}_") and name.endswith(f"_{side}"):
                out[name] = np.where(frames, np.nan, np.asarray(series[name], dtype=np.float64))
    return out


def _base(name: str) -> str:
    """The angle's name without its side."""
    base, _, side = name.rpartition("_")
    return base if side in SIDES else name


def _has(geo: Geometry, segment: str, side: str) -> bool:
    if segment in ("pelvis", "thorax"):
        return getattr(geo, segment) is not None
    return f"{segment}_{side}" in geo.axes


def missing_notes(geo: Geometry, names: Iterable[str], present: Iterable[str]) -> dict[str, str]:
    """A reason for every angle of ``names`` the skeleton does not give."""
    notes, given = {}, set(present)
    for name in names:
        if name in given:
            continue
        base, _, side = name.rpartition("_")
        base, side = (base, side) if side in SIDES else (name, "")
        lacking = [SEGMENT_WORDS[s] for s in NEEDS[base] if not _has(geo, s, side)]
        notes[name] = (
            f"{NOT_MEASURABLE}: the capture does not track the {' or the '.join(lacking)}"
            if lacking
            else f"{NOT_MEASURABLE}: the capture gives no neutral position of the foot to "
            "measure from"
        )
    return notes
