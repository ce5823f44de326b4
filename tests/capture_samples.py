"""A BVH recording's joint positions in each capture layout: for the round-trip checks
(``tests/analysis/test_sources_roundtrip.py``, ``make capture-check``) and for trying importers.

`canonical_points` reads the body parts `analysis.bvh.rigs` identifies (so any rig works) and
returns them in metres; the writers turn those points into file bytes of each layout.
"""

from __future__ import annotations

import json
from pathlib import Path

import ezc3d
import numpy as np
import numpy.typing as npt

from analysis.bvh import rigs
from analysis.bvh.errors import SkeletonMismatchError
from analysis.bvh.io import Motion
from analysis.kinematics.forward_kinematics import end_site_positions, positions
from analysis.sources.names import AZURE, MEDIAPIPE

FloatArray = npt.NDArray[np.float64]
# body part (analysis.bvh.rigs) → canonical point (analysis.sources.ik)
ROLE_POINTS = {
    "pelvis": "pelvis", "chest": "chest", "neck": "neck", "head": "head", "head_top": "head_top",
    **{f"{s}_{role}": f"{s}_{point}" for s in ("left", "right") for role, point in (
        ("upper_arm", "shoulder"), ("forearm", "elbow"), ("hand", "wrist"),
        ("upper_leg", "hip"), ("lower_leg", "knee"), ("foot", "ankle"), ("toes", "toe"))},
}  # fmt: skip

NEEDED = tuple(r for r in ROLE_POINTS if r not in ("neck", "head_top", "left_toes", "right_toes"))


def body_height(points: dict[str, FloatArray]) -> float:
    """Median head-to-ankle distance, the scale the points are measured in."""
    feet = (points["left_ankle"] + points["right_ankle"]) / 2
    return float(np.median(np.linalg.norm(points["head"] - feet, axis=1)))


def canonical_points(motion: Motion, height_m: float = 1.6) -> dict[str, FloatArray]:
    """{canonical point: (T, 3) metres} of a BVH motion, scaled to a person ``height_m`` tall
    from head to ankles (BVH units vary: cm, inches, metres)."""
    roles = rigs.identify(motion.skeleton)
    missing = [r for r in NEEDED if r not in roles]
    if missing:
        raise SkeletonMismatchError(
            "The recording has no " + ", ".join(rigs.plain_name(r) for r in missing) + "."
        )
    every = np.concatenate((positions(motion), end_site_positions(motion)), axis=1)
    points = {ROLE_POINTS[r]: every[:, k] for r, k in roles.items() if r in ROLE_POINTS}
    scale = height_m / max(body_height(points), 1e-9)
    return {name: track * scale for name, track in points.items()}


KINECT = {
    "pelvis": "SpineBase", "chest": "SpineShoulder", "neck": "Neck", "head": "Head",
    **{f"{s}_{p}": f"{name}{s.title()}" for s in ("left", "right") for p, name in (
        ("shoulder", "Shoulder"), ("elbow", "Elbow"), ("wrist", "Wrist"), ("hip", "Hip"),
        ("knee", "Knee"), ("ankle", "Ankle"), ("toe", "Foot"))},
}  # fmt: skip
POSE2SIM = {
    "pelvis": "Hip", "neck": "Neck", "head": "Head",
    **{f"{s}_{p}": f"{s[0].upper()}{name}" for s in ("left", "right") for p, name in (
        ("shoulder", "Shoulder"), ("elbow", "Elbow"), ("wrist", "Wrist"), ("hip", "Hip"),
        ("knee", "Knee"), ("ankle", "Ankle"), ("toe", "BigToe"))},
}  # fmt: skip
FLIP = np.array([1.0, -1.0, -1.0])  # y up ↔ y down (a half turn about x)


def _named(points: dict[str, FloatArray], names: dict[str, str]) -> dict[str, FloatArray]:
    return {names[k]: v for k, v in points.items() if k in names}


def kinect_wide_csv(points: dict[str, FloatArray], fps: float) -> bytes:
    tracks = _named(points, KINECT)
    n = next(iter(tracks.values())).shape[0]
    header = ["Time"] + [f"{j}_{a}" for j in tracks for a in "XYZ"]
    rows = [",".join(header)]
    for f in range(n):
        values = [f"{f / fps:.5f}"] + [f"{v:.5f}" for t in tracks.values() for v in t[f]]
        rows.append(",".join(values))
    return ("\n".join(rows) + "\n").encode()


def kinect_long_csv(points: dict[str, FloatArray], fps: float) -> bytes:
    tracks = _named(points, KINECT)
    n = next(iter(tracks.values())).shape[0]
    rows = ["time,joint,x,y,z"]
    for f in range(n):
        rows += [f"{f / fps:.5f},{j},{t[f, 0]:.5f},{t[f, 1]:.5f},{t[f, 2]:.5f}"
                 for j, t in tracks.items()]  # fmt: skip
    return ("\n".join(rows) + "\n").encode()


def _extrapolated(points: dict[str, FloatArray], a: str, b: str, share: float) -> FloatArray:
    return points[b] + share * (points[b] - points[a])


def azure_json(points: dict[str, FloatArray], fps: float) -> bytes:
    """Azure Kinect Body Tracking JSON (mm, y down); joints the points lack are placed near their
    neighbours (hand, tip and thumb beyond the wrist, clavicles at the chest, face at the head)."""
    full = dict(points)
    full.setdefault("spine", (points["pelvis"] + points["chest"]) / 2)
    full.setdefault("neck", points["chest"] + 0.35 * (points["head"] - points["chest"]))
    by_name = {"PELVIS": "pelvis", "SPINE_NAVAL": "spine", "SPINE_CHEST": "chest",
               "NECK": "neck", "HEAD": "head"}  # fmt: skip
    for s in ("left", "right"):
        up = s.upper()
        full[f"{s}_hand"] = _extrapolated(points, f"{s}_elbow", f"{s}_wrist", 0.2)
        full[f"{s}_tip"] = _extrapolated(points, f"{s}_elbow", f"{s}_wrist", 0.35)
        by_name |= {f"SHOULDER_{up}": f"{s}_shoulder", f"ELBOW_{up}": f"{s}_elbow",
                    f"WRIST_{up}": f"{s}_wrist", f"HAND_{up}": f"{s}_hand",
                    f"HANDTIP_{up}": f"{s}_tip", f"THUMB_{up}": f"{s}_hand",
                    f"CLAVICLE_{up}": "chest", f"HIP_{up}": f"{s}_hip", f"KNEE_{up}": f"{s}_knee",
                    f"ANKLE_{up}": f"{s}_ankle", f"FOOT_{up}": f"{s}_toe",
                    f"EYE_{up}": "head", f"EAR_{up}": "head"}  # fmt: skip
    by_name["NOSE"] = "head"
    stack = np.stack([full[by_name[j]] for j in AZURE], axis=1) * FLIP * 1000.0
    frames = [
        {"timestamp_usec": round(f * 1e6 / fps),
         "bodies": [{"body_id": 1, "joint_positions": stack[f].round(2).tolist()}]}
        for f in range(stack.shape[0])
    ]  # fmt: skip
    return json.dumps({"joint_names": list(AZURE), "frames": frames}).encode()


def trc(points: dict[str, FloatArray], fps: float) -> bytes:
    tracks = _named(points, POSE2SIM)
    n = next(iter(tracks.values())).shape[0]
    names = list(tracks)
    lines = [
        "PathFileType\t4\t(X/Y/Z)\tsample.trc",
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame"
        "\tOrigNumFrames",
        f"{fps:g}\t{fps:g}\t{n}\t{len(names)}\tmm\t{fps:g}\t1\t{n}",
        "Frame#\tTime\t" + "\t\t\t".join(names) + "\t\t",
        "\t\t" + "\t".join(f"{a}{k + 1}" for k in range(len(names)) for a in "XYZ"),
    ]
    for f in range(n):
        values = "\t".join(f"{v * 1000:.3f}" for t in tracks.values() for v in t[f])
        lines.append(f"{f + 1}\t{f / fps:.5f}\t{values}")
    return ("\n".join(lines) + "\n").encode()


def c3d(points: dict[str, FloatArray], fps: float, path: str) -> bytes:
    """A C3D file written by ezc3d's own writer (keypoint labels, millimetres)."""
    tracks = _named(points, POSE2SIM)
    data = ezc3d.c3d()
    data["parameters"]["POINT"]["RATE"]["value"] = [fps]
    data["parameters"]["POINT"]["LABELS"]["value"] = list(tracks)
    data["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    stack = np.stack(list(tracks.values()), axis=1) * 1000.0  # (T, N, 3)
    values = np.ones((4, stack.shape[1], stack.shape[0]))
    values[:3] = np.transpose(stack, (2, 1, 0))
    data["data"]["points"] = values
    data.write(path)
    return Path(path).read_bytes()


def mediapipe_json(points: dict[str, FloatArray], fps: float) -> bytes:
    """33 world landmarks per frame (y down, metres, origin between the hips), all visible."""
    full = {name: points[name] for name in points}
    origin = (points["left_hip"] + points["right_hip"]) / 2
    place = {}
    for name in MEDIAPIPE:
        side = "left" if name.startswith("left") else "right"
        part = name.removeprefix(f"{side}_")
        if name in full:
            place[name] = full[name]
        elif part == "foot_index":
            place[name] = full[f"{side}_toe"]
        elif part in ("pinky", "index", "thumb"):
            place[name] = _extrapolated(points, f"{side}_elbow", f"{side}_wrist", 0.3)
        elif part == "heel":
            place[name] = full[f"{side}_ankle"]
        else:
            place[name] = full["head"]
    stack = (np.stack([place[n] for n in MEDIAPIPE], axis=1) - origin[:, None]) * FLIP
    frames = [[{"x": x, "y": y, "z": z, "visibility": 0.99} for x, y, z in frame.round(5).tolist()]
              for frame in stack]  # fmt: skip
    return json.dumps({"fps": fps, "frames": frames}).encode()


LAYOUTS = ("kinect_wide", "kinect_long", "azure", "trc", "c3d", "mediapipe")
SUFFIX = {"kinect_wide": ".csv", "kinect_long": ".csv", "azure": ".json", "trc": ".trc",
          "c3d": ".c3d", "mediapipe": ".json"}  # fmt: skip


def write_layout(layout: str, points: dict[str, FloatArray], fps: float, folder: Path) -> Path:
    """The points written as ``layout`` into ``folder``; returns the file."""
    path = folder / f"{layout}{SUFFIX[layout]}"
    if layout == "c3d":
        c3d(points, fps, str(path))
        return path
    writer = {"kinect_wide": kinect_wide_csv, "kinect_long": kinect_long_csv,
              "azure": azure_json, "trc": trc, "mediapipe": mediapipe_json}[layout]  # fmt: skip
    path.write_bytes(writer(points, fps))
    return path
