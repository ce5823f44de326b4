"""Vicon recordings of ART targets as the KERAAL data set writes them: one frame per line, no
header, 17 rigid targets × (x y z qx qy qz qw): the target's position (millimetres) and global
orientation, in the order `TARGETS`.

Targets sit on the segments, not at the joints, so each joint centre is found as the point that
moves with both segments it joins (the least-squares "symmetrical centre of rotation": fixed in
the upper arm's target frame and in the forearm's at once, over the whole take). Where a take
barely moves a joint, that fit is pulled towards the midpoint of the two targets (a weak prior),
so a still leg gets a plausible knee rather than a wild one. The pelvis and the chest are the
middles of the hip and shoulder centres, as a Kinect places its spine base and spine shoulder.
A limb whose two middle targets are labelled the other way round (the upper-arm target nearer the
hand, the forearm's nearer the shoulder) is read with them swapped back (`in_chain_order`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from analysis.sources.errors import CaptureFileError
from analysis.sources.tables import FloatArray, check_frames, z_up_to_y_up

TARGETS = (
    "Right Forearm", "Left Forearm", "Right Arm", "Left Arm", "Chest", "Right Thigh", "Left Thigh",
    "Right Shoulder", "Left Shoulder", "Right Hand", "Left Hand", "Right Foot", "Left Foot",
    "Hips", "Head", "Right Tibia", "Left Tibia",
)  # fmt: skip
VALUES_PER_TARGET = 7
WIDTH = len(TARGETS) * VALUES_PER_TARGET
ART_FPS = 60.0  # ART DTrack's usual rate; the files carry no times
# Joint centres: (canonical point, the target above, the target below).
CENTRES = (
    *(
        (f"{s.lower()}_{joint}", f"{s} {a}", f"{s} {b}")
        for s in ("Left", "Right")
        for joint, a, b in (
            ("shoulder", "Shoulder", "Arm"), ("elbow", "Arm", "Forearm"),
            ("wrist", "Forearm", "Hand"), ("knee", "Thigh", "Tibia"), ("ankle", "Tibia", "Foot"),
        )
    ),
    ("left_hip", "Hips", "Left Thigh"), ("right_hip", "Hips", "Right Thigh"),
    ("neck", "Chest", "Head"),
)  # fmt: skip
# Weight of the prior against the fit, per frame (mm² of fit error per mm² of departure): small,
# so a joint that moves follows its fit and one that does not stays between its targets.
PRIOR = 0.1


def read_targets(rows: list[list[float] | None]) -> dict[str, tuple[FloatArray, FloatArray]]:
    """{target name: (positions (T, 3) in the file's unit, rotations (T, 3, 3))}; NaN where the
    target was lost (an empty line, or an orientation of zeros)."""
    check_frames(len(rows))
    values = np.full((len(rows), WIDTH), np.nan)
    for r, row in enumerate(rows):
        if row is None:
            continue
        if len(row) != WIDTH:
            raise CaptureFileError(
                f"Line {r + 1} holds {len(row)} values; the Vicon target text holds "
                f"{len(TARGETS)} targets × 7 (x y z qx qy qz qw), {WIDTH} per line."
            )
        values[r] = row
    out = {}
    for k, name in enumerate(TARGETS):
        block = values[:, VALUES_PER_TARGET * k : VALUES_PER_TARGET * (k + 1)]
        quat = block[:, 3:]
        lost = ~np.all(np.isfinite(block), axis=1) | (np.linalg.norm(quat, axis=1) < 0.5)
        rotations = np.full((len(rows), 3, 3), np.nan)
        if (~lost).any():
            rotations[~lost] = Rotation.from_quat(quat[~lost]).as_matrix()
        positions = block[:, :3].copy()
        positions[lost] = np.nan
        out[name] = (positions, rotations)
    return out


# Each limb's chain of targets, from the trunk's end to the far end: the two middle targets are
# told apart by which end they are nearer to.
CHAINS = (
    *((f"{s} Shoulder", f"{s} Arm", f"{s} Forearm", f"{s} Hand") for s in ("Left", "Right")),
    *(("Hips", f"{s} Thigh", f"{s} Tibia", f"{s} Foot") for s in ("Left", "Right")),
)


def _distance(a: FloatArray, b: FloatArray) -> float:
    """Median distance over the frames where both targets are seen (NaN where none are)."""
    apart = np.linalg.norm(a - b, axis=1)
    apart = apart[np.isfinite(apart)]
    return float(np.median(apart)) if apart.size else float("nan")


def in_chain_order(
    targets: dict[str, tuple[FloatArray, FloatArray]],
) -> tuple[dict[str, tuple[FloatArray, FloatArray]], list[str]]:
    """The targets with any limb's two middle targets swapped back where the file labels them the
    other way round (the upper-arm target nearer the hand than the forearm's and farther from the
    shoulder: KERAAL's ELK and RTK takes label the left arm's so), and a note per swap."""
    out, notes = dict(targets), []
    for top, near, far, end in CHAINS:
        if not {top, near, far, end} <= targets.keys():
            continue
        p = {name: targets[name][0] for name in (top, near, far, end)}
        swapped = _distance(p[top], p[near]) > _distance(p[top], p[far]) and _distance(
            p[end], p[far]
        ) > _distance(p[end], p[near])
        if swapped:
            out[near], out[far] = targets[far], targets[near]
            notes.append(
                f"The {near.lower()} and {far.lower()} targets were labelled the other way round "
                "(each lies where the other belongs); they were swapped back."
            )
    return out, notes


def joint_centres(targets: dict[str, tuple[FloatArray, FloatArray]]) -> dict[str, FloatArray]:
    """Canonical points (the file's unit) from the targets (see the module docstring)."""
    points: dict[str, FloatArray] = {}
    hips = hip_priors(targets)
    for name, above, below in CENTRES:
        points[name] = centre(targets[above], targets[below], hips.get(name))
    points["chest"] = (points["left_shoulder"] + points["right_shoulder"]) / 2
    points["head"] = targets["Head"][0]
    for side in ("Left", "Right"):
        points[f"{side.lower()}_hand_tip"] = targets[f"{side} Hand"][0]
        points[f"{side.lower()}_toe"] = targets[f"{side} Foot"][0]
    return z_up_to_y_up(points)


# The hip joints from the pelvis target (worn on the front of the pelvis, as the KERAAL takes
# show: it lies in front of the shoulders' targets): millimetres back, to the side and down, a
# population rule like Bell's for Plug-in Gait. Seated or standing takes barely move the hips
# against the thighs, so this prior is what places them, weighted `HIP_PRIOR`.
HIP_BACK_MM, HIP_SIDE_MM, HIP_DOWN_MM = 80.0, 90.0, 80.0
HIP_PRIOR = 1.0


def hip_priors(targets: dict[str, tuple[FloatArray, FloatArray]]) -> dict[str, FloatArray]:
    """Where the population rule puts each hip joint, per frame (z up, x forward in the file)."""
    pelvis = targets["Hips"][0]
    lateral = targets["Left Thigh"][0] - targets["Right Thigh"][0]
    lateral[:, 2] = 0.0
    lateral /= np.maximum(np.linalg.norm(lateral, axis=1, keepdims=True), 1e-9)
    up = np.array([0.0, 0.0, 1.0])
    forward = np.cross(lateral, up)  # left × up = forward (right-handed)
    base = pelvis - HIP_BACK_MM * forward - HIP_DOWN_MM * up
    return {"left_hip": base + HIP_SIDE_MM * lateral, "right_hip": base - HIP_SIDE_MM * lateral}


def centre(
    a: tuple[FloatArray, FloatArray],
    b: tuple[FloatArray, FloatArray],
    prior: FloatArray | None = None,
) -> FloatArray:
    """The point fixed in both targets' frames (T, 3): least squares over the frames where both
    are seen, ``R_a c_a + p_a = R_b c_b + p_b``, with a prior (by default, weakly, the two
    targets' midpoint)."""
    (pa, ra), (pb, rb) = a, b
    ok = np.all(np.isfinite(pa), axis=1) & np.all(np.isfinite(pb), axis=1)
    if prior is not None:
        ok &= np.all(np.isfinite(prior), axis=1)
    if ok.sum() < 2:
        return np.full_like(pa, np.nan)
    middle = (pa[ok] + pb[ok]) / 2 if prior is None else prior[ok]
    prior_a = np.median(np.einsum("tji,tj->ti", ra[ok], middle - pa[ok]), axis=0)
    prior_b = np.median(np.einsum("tji,tj->ti", rb[ok], middle - pb[ok]), axis=0)
    system = np.concatenate((ra[ok], -rb[ok]), axis=2).reshape(-1, 6)
    rhs = (pb[ok] - pa[ok]).reshape(-1)
    weight = np.sqrt((PRIOR if prior is None else HIP_PRIOR) * ok.sum())
    system = np.concatenate((system, weight * np.eye(6)))
    rhs = np.concatenate((rhs, weight * np.concatenate((prior_a, prior_b))))
    solution = np.linalg.lstsq(system, rhs, rcond=None)[0]
    in_a = np.einsum("tij,j->ti", ra, solution[:3]) + pa
    in_b = np.einsum("tij,j->ti", rb, solution[3:]) + pb
    return (in_a + in_b) / 2
