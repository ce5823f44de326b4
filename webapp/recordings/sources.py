"""What each capture source measures well and badly, as the recording page says it beside the
joint angles (docs/CAPTURE_SOURCES.md holds the longer account and the measurements)."""

from __future__ import annotations

from dataclasses import dataclass

from analysis.sources import RecordingSource


@dataclass(frozen=True)
class SourceReliability:
    name: str
    reliable: str
    less_reliable: str


RELIABILITY = {
    "bvh": SourceReliability(
        "a motion-capture file (BVH)",
        "every angle the recording's skeleton has",
        "only what the capture system itself got wrong",
    ),
    "kinect": SourceReliability(
        "a depth camera (Kinect)",
        "hips, knees, shoulders, elbows and the trunk facing the camera",
        "ankles and feet, hands and wrists, and any joint the body hides from the camera",
    ),
    "trc": SourceReliability(
        "marker or keypoint positions (.trc)",
        "hips, knees, ankles and elbows",
        "the trunk, estimated from the neck, hips and shoulders, and twists of the arms and thighs",
    ),
    "c3d": SourceReliability(
        "a marker system (C3D)",
        "marker positions, to about a millimetre",
        "joint centres, estimated from skin markers, and twists of the arms and thighs",
    ),
    "vicon": SourceReliability(
        "a marker system (Vicon targets)",
        "arm raising, elbow bending and the trunk's bending and turning, at a high frame rate",
        "joint centres, found from how the targets move: a joint the take barely moves is "
        "placed roughly, so its angle reads roughly",
    ),
    "mediapipe": SourceReliability(
        "body landmarks from a camera (MediaPipe)",
        "arm and leg angles facing the camera",
        "movement toward or away from the camera, the trunk, ankles and feet",
    ),
    "camera": SourceReliability(
        "the browser's camera, live (body landmarks found on the device)",
        "arm and leg angles facing the camera",
        "movement toward or away from the camera, the trunk, ankles and feet",
    ),
    "video": SourceReliability(
        "a phone video",
        "knee, hip and elbow bending seen from the side, arm raising seen from the front",
        "movement toward or away from the camera (one camera guesses depth), the trunk's "
        "turning, ankles and feet",
    ),
}


def source_reliability(source: RecordingSource) -> SourceReliability:
    return kind_reliability(source.kind)


def kind_reliability(kind: str) -> SourceReliability:
    """By the source's kind alone (an exercise's reference, which has no analysis result)."""
    return RELIABILITY.get(kind, RELIABILITY["bvh"])
