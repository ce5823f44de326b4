"""Point names of the capture sources → the canonical points `analysis.sources.ik` solves for.

Names are compared lower-case without punctuation, so ``SpineBase``, ``SPINE_BASE`` and
``spine_base`` are one name. Covered: Kinect v2 (25 joints), Azure Kinect Body Tracking (32),
OpenPose BODY_25 / HALPE-26 keypoints as Pose2Sim and OpenCap write them in ``.trc`` files, and
MediaPipe/BlazePose's 33 landmarks (`MEDIAPIPE`).
"""

from __future__ import annotations

import re

_SIDED = {
    # canonical part: names with {L}/{l}/{Left}/{LEFT}/{left} standing for the side
    "shoulder": ("Shoulder{Left}", "{L}Shoulder", "SHOULDER_{LEFT}", "{left}_shoulder"),
    "elbow": ("Elbow{Left}", "{L}Elbow", "ELBOW_{LEFT}", "{left}_elbow"),
    "wrist": ("Wrist{Left}", "{L}Wrist", "WRIST_{LEFT}", "{left}_wrist"),
    "hand_tip": ("HandTip{Left}", "HANDTIP_{LEFT}", "{left}_index"),
    "hip": ("Hip{Left}", "{L}Hip", "HIP_{LEFT}", "{left}_hip"),
    "knee": ("Knee{Left}", "{L}Knee", "KNEE_{LEFT}", "{left}_knee"),
    "ankle": ("Ankle{Left}", "{L}Ankle", "ANKLE_{LEFT}", "{left}_ankle"),
    "toe": ("Foot{Left}", "{L}BigToe", "FOOT_{LEFT}", "{left}_foot_index"),
}
_CENTRE = {
    "pelvis": ("SpineBase", "PELVIS", "Hip", "MidHip"),
    "spine": ("SpineMid", "SPINE_NAVAL"),
    "chest": ("SpineShoulder", "SPINE_CHEST"),
    "neck": ("Neck",),
    "head": ("Head",),
}
# Points some sources give that the skeleton does not use (reported as not used).
MEDIAPIPE = (
    "nose", "left_eye_inner", "left_eye", "left_eye_outer", "right_eye_inner", "right_eye",
    "right_eye_outer", "left_ear", "right_ear", "mouth_left", "mouth_right", "left_shoulder",
    "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_pinky",
    "right_pinky", "left_index", "right_index", "left_thumb", "right_thumb", "left_hip",
    "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle", "left_heel",
    "right_heel", "left_foot_index", "right_foot_index",
)  # fmt: skip
AZURE = (
    "PELVIS", "SPINE_NAVAL", "SPINE_CHEST", "NECK", "CLAVICLE_LEFT", "SHOULDER_LEFT",
    "ELBOW_LEFT", "WRIST_LEFT", "HAND_LEFT", "HANDTIP_LEFT", "THUMB_LEFT", "CLAVICLE_RIGHT",
    "SHOULDER_RIGHT", "ELBOW_RIGHT", "WRIST_RIGHT", "HAND_RIGHT", "HANDTIP_RIGHT", "THUMB_RIGHT",
    "HIP_LEFT", "KNEE_LEFT", "ANKLE_LEFT", "FOOT_LEFT", "HIP_RIGHT", "KNEE_RIGHT", "ANKLE_RIGHT",
    "FOOT_RIGHT", "HEAD", "NOSE", "EYE_LEFT", "EAR_LEFT", "EYE_RIGHT", "EAR_RIGHT",
)  # fmt: skip
KINECT_V2 = (
    "SpineBase", "SpineMid", "Neck", "Head", "ShoulderLeft", "ElbowLeft", "WristLeft", "HandLeft",
    "ShoulderRight", "ElbowRight", "WristRight", "HandRight", "HipLeft", "KneeLeft", "AnkleLeft",
    "FootLeft", "HipRight", "KneeRight", "AnkleRight", "FootRight", "SpineShoulder",
    "HandTipLeft", "ThumbLeft", "HandTipRight", "ThumbRight",
)  # fmt: skip


def key(name: str) -> str:
    """A name compared without case, spaces or punctuation."""
    return re.sub(r"[^0-9a-z]", "", name.lower())


def _table() -> dict[str, str]:
    table = {key(n): part for part, names in _CENTRE.items() for n in names}
    for part, patterns in _SIDED.items():
        for side in ("left", "right"):
            marks = {"L": side[0].upper(), "Left": side.title(), "LEFT": side.upper(), "left": side}
            for pattern in patterns:
                table[key(pattern.format(**marks))] = f"{side}_{part}"
    return table


CANONICAL = _table()


def canonical(name: str) -> str | None:
    """The canonical point a source's name stands for, or None if the skeleton does not use it."""
    return CANONICAL.get(key(name))
