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

Only what a body can do, and only what this recording measures (`compensation_measures`):

- each measure is bounded by what the joint can do about the posture the recording holds
  (`REACH`, degrees from its median): frames beyond are the capture losing a joint (a Kinect
  turning a side-on body's shoulders through 160°) and are left out; more than
  `MAX_BEYOND_SHARE` of them, and the measure is not measurable in this recording;
- a measure whose frame-to-frame noise (`jitter`: the range the jumps alone add) exceeds the
  amount it would flag (`LIMIT_DEG`) is "not measurable reliably in this recording", with
  that reason, never a finding (Kinect knee jitter read as a knee falling in by 37°).

A movement the exercise trains is never a compensation (`trained`): a measure the
demonstration itself moves through `TRAINED_FACTOR` times its limit (a trunk-rotation
exercise turns the trunk, a shrug lifts the shoulders) is not checked in that exercise.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt
from scipy.ndimage import uniform_filter1d

FloatArray = npt.NDArray[np.float64]
LIMIT_DEG = {"trunk_rotation": 15.0, "shoulder_hike": 10.0, "knee_valgus": 15.0}
SIDES = ("left", "right")
# How far each part can move from the posture it holds (degrees, toward − / + of the measure):
# the trunk turns about 45° each way over the pelvis (AAOS thoracolumbar rotation) and the
# shoulder girdle's protraction adds up to 15° at the shoulder line; the shoulder girdle rises
# about 45° in a shrug and drops about 30° as the arm reaches back and down (Kapandji, The
# Physiology of the Joints, vol. 1; the shoulder joint's centre moves with the arm); the knee
# falls up to 30° inside the hip–ankle line in the loosest knees, and sits up to 45° outside
# it in squats and lunges with the knees out over the toes.
REACH: dict[str, tuple[float, float]] = {
    "trunk_rotation": (-60.0, 60.0),
    "shoulder_hike": (-35.0, 45.0),
    "knee_valgus": (-45.0, 30.0),
}
REACH_SOURCE = "AAOS thoracolumbar rotation; Kapandji vol. 1 (shoulder girdle); knee in squats"
MAX_BEYOND_SHARE = 0.05  # of the tracked frames, as for the clinical angles
JITTER_FRAMES = 5  # a mean over this many frames (1/6 s at 30 fps) is the movement itself
MIN_FRAMES = 2 * JITTER_FRAMES  # fewer: too short to tell noise from movement
TRAINED_FACTOR = 2.0  # the demonstration moves it this many times its limit: the exercise's own
NOT_MEASURABLE = "not measurable in this recording"
NOT_RELIABLE = "not measurable reliably in this recording"
WORDS = {
    "trunk_rotation": "the trunk's turn", "shoulder_hike": "the {side} shoulder's rise",
    "knee_valgus": "the {side} knee's line over the foot",
}  # fmt: skip


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


def raw_series(pos: FloatArray, roles: Mapping[str, int], up: FloatArray) -> dict[str, FloatArray]:
    """Every compensation the rig's joints allow (module docstring), degrees per frame, as read
    (neither bounded nor checked for noise)."""
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


def base_of(name: str) -> str:
    """The measure's name without its side ("knee_valgus_left" → "knee_valgus")."""
    return next((k for k in LIMIT_DEG if name.startswith(k)), name)


def jitter(values: FloatArray, frames: int = JITTER_FRAMES) -> float:
    """The range (degrees) a series' frame-to-frame noise alone adds: twice the 90th percentile
    of its distance from its running mean over ``frames`` frames (a movement at a person's pace
    hardly leaves it; a reading flipping between two values every frame does); 0 for a series
    too short to tell."""
    kept = np.asarray(values, dtype=np.float64)
    kept = kept[np.isfinite(kept)]
    if kept.size < 2 * frames:
        return 0.0
    smooth = uniform_filter1d(kept, size=frames, mode="nearest")
    return float(2.0 * np.percentile(np.abs(kept - smooth), 90.0))


def _words(name: str) -> str:
    side = name.rsplit("_", 1)[-1] if name.endswith(SIDES) else ""
    return WORDS[base_of(name)].format(side=side)


def checked(name: str, read: FloatArray) -> tuple[FloatArray | None, str]:
    """One measure bounded by what the body can do about its held posture and checked for
    noise (module docstring): the series (frames beyond left out) or None and why not."""
    values = np.asarray(read, dtype=np.float64)
    tracked = np.isfinite(values)
    if not tracked.any():
        return None, f"{NOT_MEASURABLE}: the joints it needs were not tracked"
    low, high = REACH[base_of(name)]
    off = values - np.median(values[tracked])
    beyond = tracked & ((off < low) | (off > high))
    if beyond.sum() > MAX_BEYOND_SHARE * tracked.sum():
        share = round(100 * beyond.sum() / tracked.sum())
        return None, (
            f"{NOT_MEASURABLE}: in {share} % of the frames {_words(name)} reads beyond what a "
            f"body can do ({low:.0f}° to {high:.0f}° from its usual position); the capture lost "
            "track of a joint"
        ).replace("-", "−")
    kept = np.where(beyond, np.nan, values)
    noise, limit = jitter(kept), limit_of(name) or 0.0
    if noise > limit:
        return None, (
            f"{NOT_RELIABLE}: {_words(name)} jumps by about {noise:.0f}° from one frame to the "
            f"next, more than the {limit:.0f}° it would be corrected for"
        )
    return kept, ""


def compensation_measures(
    pos: FloatArray, roles: Mapping[str, int], up: FloatArray
) -> tuple[dict[str, FloatArray], dict[str, str]]:
    """The compensations this recording measures (bounded and steady: `checked`), degrees per
    frame, and for each other one the rig's joints allow, why not (plain words)."""
    series, notes = {}, {}
    for name, read in raw_series(pos, roles, up).items():
        kept, why = checked(name, read)
        if kept is None:
            notes[name] = why
        else:
            series[name] = kept
    return series, notes


def compensation_series(
    pos: FloatArray, roles: Mapping[str, int], up: FloatArray
) -> dict[str, FloatArray]:
    """The compensations this recording measures (`compensation_measures`), degrees per frame:
    a measure beyond what a body does, or noisier than what it would flag, is left out."""
    return compensation_measures(pos, roles, up)[0]


def span_of(name: str) -> float:
    """The most a compensation can range over (degrees): its whole `REACH`."""
    low, high = REACH[base_of(name)]
    return high - low


def trained(ranges: Mapping[str, float]) -> set[str]:
    """The compensation measures the exercise itself trains, from the demonstration's ranges
    (degrees per name, as `analysis.assessment.findings.Reference.ranges`): those it moves
    through at least `TRAINED_FACTOR` times their limit, each in its own plane (the trunk's
    turn about the vertical, a shoulder's rise along the trunk, a knee's sideways line), so the
    patient is never told to keep still what the exercise moves."""
    return {
        name
        for name, value in ranges.items()
        if (limit := limit_of(name)) is not None and value >= TRAINED_FACTOR * limit
    }


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
