"""Capture sources other than BVH: Kinect and Azure Kinect joint positions (with or without a
header, `kinect_text`), ``.trc`` and C3D marker files, Vicon ART targets (`vicon`), MediaPipe and
BlazePose landmarks (`blazepose`), each turned into a `Motion` by one inverse kinematics (`ik`).

Pipeline: `read_recording(name, content)` is how the command line, the upload and the worker read
any recording (BVH goes to `analysis.bvh.read`); `analysis.kinematics.map_onto` then puts the
result on the exercise's skeleton like any other rig. The result's ``source`` is
`RecordingSource`.
"""

from analysis.sources.errors import CaptureFileError
from analysis.sources.mediapipe import motion_from_landmarks
from analysis.sources.read import SUFFIXES, read_recording
from analysis.sources.report import ImportedRecording, ImportReport, RecordingSource

__all__ = [
    "SUFFIXES",
    "CaptureFileError",
    "ImportReport",
    "ImportedRecording",
    "RecordingSource",
    "motion_from_landmarks",
    "read_recording",
]
