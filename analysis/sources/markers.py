"""Joint centres from a Plug-in Gait marker set (lower and upper body), estimated simply.

Markers are on the skin, not at the joints, so the centres are estimates (see
``docs/CAPTURE_SOURCES.md``):

- pelvis: the mean of LASI, RASI, LPSI, RPSI (SACR for both PSIs when it is used instead);
- hip joint centres: Bell's rule from the pelvis: from the midpoint of the ASIS markers, with the
  ASIS width W, 0.36 W to the side, 0.19 W back and 0.30 W down;
- knees and ankles: the lateral markers (LKNE, LANK) moved 5 cm and 3.5 cm towards the body's
  midline (half a typical knee and ankle width); toes: LTOE;
- shoulders: LSHO moved 5 cm down the trunk; elbows: LELB; wrists: the mean of LWRA and LWRB
  (or LWRA alone); hand tips: LFIN;
- chest: the mean of CLAV and C7; head: the mean of the four head markers (LFHD, RFHD, LBHD,
  RBHD). The neck is left to the solver's estimate.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from analysis.sources.tables import FloatArray

PELVIS = ("LASI", "RASI")
HEAD = ("LFHD", "RFHD", "LBHD", "RBHD")
KNEE_HALF_WIDTH_M, ANKLE_HALF_WIDTH_M, SHOULDER_DROP_M = 0.05, 0.035, 0.05


def is_plug_in_gait(names: set[str]) -> bool:
    return set(PELVIS) <= {n.upper() for n in names}


def _unit(v: FloatArray) -> FloatArray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9)


def _mean(m: Mapping[str, FloatArray], names: tuple[str, ...]) -> FloatArray | None:
    found = [m[n] for n in names if n in m]
    return np.mean(found, axis=0) if found else None


def joint_centres(markers: Mapping[str, FloatArray]) -> dict[str, FloatArray]:
    """Canonical points (metres) from Plug-in Gait markers (upper-case names, metres)."""
    m = {k.upper(): v for k, v in markers.items()}
    back = _mean(m, ("LPSI", "RPSI")) if "LPSI" in m else m.get("SACR")
    front = (m["LASI"] + m["RASI"]) / 2
    points: dict[str, FloatArray] = {}
    width = np.linalg.norm(m["LASI"] - m["RASI"], axis=1, keepdims=True)
    lateral = _unit(m["LASI"] - m["RASI"])
    forward = _unit(front - back) if back is not None else None
    points["pelvis"] = (front + back) / 2 if back is not None else front
    if forward is not None:
        forward = _unit(forward - np.sum(forward * lateral, axis=1, keepdims=True) * lateral)
        up = np.cross(forward, lateral)  # right-handed: forward × left = up
        for side, sign in (("left", 1.0), ("right", -1.0)):
            points[f"{side}_hip"] = front + width * (
                sign * 0.36 * lateral - 0.19 * forward - 0.30 * up
            )
    inward = {"left": -lateral, "right": lateral}
    for side, s in (("left", "L"), ("right", "R")):
        if f"{s}KNE" in m:
            points[f"{side}_knee"] = m[f"{s}KNE"] + KNEE_HALF_WIDTH_M * inward[side]
        if f"{s}ANK" in m:
            points[f"{side}_ankle"] = m[f"{s}ANK"] + ANKLE_HALF_WIDTH_M * inward[side]
        _copy(points, f"{side}_toe", m.get(f"{s}TOE"))
        _copy(points, f"{side}_elbow", m.get(f"{s}ELB"))
        _copy(points, f"{side}_wrist", _mean(m, (f"{s}WRA", f"{s}WRB")))
        _copy(points, f"{side}_hand_tip", m.get(f"{s}FIN"))
    _copy(points, "chest", _mean(m, ("CLAV", "C7")))
    _copy(points, "head", _mean(m, HEAD))
    trunk_down = _unit(points["pelvis"] - points["chest"]) if "chest" in points else None
    for side, s in (("left", "L"), ("right", "R")):
        if f"{s}SHO" in m and trunk_down is not None:
            points[f"{side}_shoulder"] = m[f"{s}SHO"] + SHOULDER_DROP_M * trunk_down
    return points


def _copy(points: dict[str, FloatArray], name: str, track: FloatArray | None) -> None:
    if track is not None:
        points[name] = track
