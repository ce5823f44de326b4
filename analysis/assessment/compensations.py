"""Compensations a therapist looks for, measured from joint positions (issue 26): the trunk
turning, a shoulder hiked, a knee falling inward (valgus). The trunk's lean is a clinical angle
(`analysis.clinical`); its posture held through the movement is a finding of
`analysis.assessment.findings` (``held``).

Inputs are the world positions of every joint (F, J, 3), the joints' body roles (role →
index, as `analysis.clinical.body.find_joints` names them: "hip_left", "shoulder_right",
"neck", …) and the file's vertical. Each measure is a series in degrees, made only where the rig
has the joints it needs:

- ``trunk_rotation``: the shoulder line (left → right shoulder) against the hip line, about
  the vertical (both lines projected on the horizontal plane).
- ``shoulder_hike_<side>``: how far the neck → shoulder line rises above the plane
  perpendicular to the trunk (pelvis → neck): a shrug raises it.
- ``knee_valgus_<side>``: how far the knee falls inside the hip → ankle line (along the hip
  line, horizontal), as an angle seen from the thigh (asin of the offset over the thigh's
  length), positive inward.

`analysis.assessment.findings` compares each measure's range over a repetition with the tutor's
(``extra`` when it exceeds it by more than `LIMIT_DEG`: the patient turned, hiked or let the
knee fall in more than the demonstration).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
LIMIT_DEG = {"trunk_rotation": 15.0, "shoulder_hike": 10.0, "knee_valgus": 15.0}
SIDES = ("left", "right")


def _unit(v: FloatArray) -> FloatArray:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, norm, out=np.zeros_like(v), where=norm > 1e-9)


def _flat(v: FloatArray, normal: FloatArray) -> FloatArray:
    """``v`` (F, 3) with its component along ``normal`` ((3,) or (F, 3), unit) removed."""
    return v - np.sum(v * normal, axis=-1, keepdims=True) * normal


def _signed_angle(a: FloatArray, b: FloatArray, axis: FloatArray) -> FloatArray:
    """Degrees from ``a`` to ``b`` about ``axis`` (vectors in the plane normal to it)."""
    cross = np.sum(np.cross(a, b) * axis, axis=-1)
    return np.degrees(np.arctan2(cross, np.sum(a * b, axis=-1)))


def trunk_rotation(pos: FloatArray, roles: Mapping[str, int], up: FloatArray) -> FloatArray:
    """The shoulder line against the hip line about the vertical (degrees)."""
    shoulders = pos[:, roles["shoulder_right"]] - pos[:, roles["shoulder_left"]]
    hips = pos[:, roles["hip_right"]] - pos[:, roles["hip_left"]]
    return _signed_angle(_unit(_flat(hips, up)), _unit(_flat(shoulders, up)), up)


def shoulder_hike(pos: FloatArray, roles: Mapping[str, int], side: str) -> FloatArray:
    """The neck → shoulder line's elevation above the plane across the trunk (degrees)."""
    trunk = _unit(pos[:, roles["neck"]] - pos[:, roles["pelvis"]])
    line = _unit(pos[:, roles[f"shoulder_{side}"]] - pos[:, roles["neck"]])
    return np.degrees(np.arcsin(np.clip(np.sum(line * trunk, axis=-1), -1.0, 1.0)))


def knee_valgus(pos: FloatArray, roles: Mapping[str, int], side: str, up: FloatArray) -> FloatArray:
    """How far the knee falls inside the hip → ankle line, as the angle of that offset seen
    from the thigh: asin(inward offset / thigh length), degrees, + inward. Bounded and steady
    in a deep squat, where the frontal-plane angle between thigh and shank is undefined."""
    hip, knee, ankle = (pos[:, roles[f"{j}_{side}"]] for j in ("hip", "knee", "ankle"))
    outward = pos[:, roles[f"hip_{side}"]] - pos[:, roles[f"hip_{SIDES[side == 'left']}"]]
    outward = _unit(_flat(outward, up))
    inward = -np.sum((knee - (hip + ankle) / 2) * outward, axis=-1)
    thigh = np.linalg.norm(knee - hip, axis=-1)
    ratio = np.divide(inward, thigh, out=np.zeros_like(inward), where=thigh > 1e-9)
    return np.degrees(np.arcsin(np.clip(ratio, -1.0, 1.0)))


def compensation_series(
    pos: FloatArray, roles: Mapping[str, int], up: FloatArray
) -> dict[str, FloatArray]:
    """Every compensation the rig's joints allow (module docstring), degrees per frame."""
    out: dict[str, FloatArray] = {}
    up = _unit(np.asarray(up, dtype=np.float64))
    if {"shoulder_left", "shoulder_right", "hip_left", "hip_right"} <= set(roles):
        out["trunk_rotation"] = trunk_rotation(pos, roles, up)
    for side in SIDES:
        if {f"shoulder_{side}", "neck", "pelvis"} <= set(roles):
            out[f"shoulder_hike_{side}"] = shoulder_hike(pos, roles, side)
        if {"hip_left", "hip_right", f"knee_{side}", f"ankle_{side}"} <= set(roles):
            out[f"knee_valgus_{side}"] = knee_valgus(pos, roles, side, up)
    return out


def limit_of(name: str) -> float | None:
    """The threshold of a compensation's name ("knee_valgus_left" → 10°); None for others."""
    return next((v for k, v in LIMIT_DEG.items() if name.startswith(k)), None)


def stretch(series: Mapping[str, FloatArray], start: int, end: int) -> dict[str, FloatArray]:
    """Each series over frames start..end (inclusive), without frames it could not measure."""
    out = {}
    for name, values in series.items():
        part = values[start : end + 1]
        part = part[np.isfinite(part)]
        if part.size:
            out[name] = part
    return out
