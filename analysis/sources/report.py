"""What an importer found in a capture file, and the short source record a result keeps."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from analysis.bvh.io import Motion

BoolArray = npt.NDArray[np.bool_]

KINDS = ("bvh", "kinect", "trc", "c3d", "mediapipe", "video", "vicon", "camera")


@dataclass(frozen=True)
class RecordingSource:
    """The result's ``source``: which kind of capture the recording came from and how many of its
    joints (or markers, landmarks) the analysis used."""

    kind: str = "bvh"
    joints: int = 0

    def to_json(self) -> dict[str, object]:
        return {"kind": self.kind, "joints": self.joints}

    @classmethod
    def from_json(cls, data: object) -> RecordingSource:
        """Runs stored before capture sources were accepted were all BVH files."""
        if not isinstance(data, dict):
            return cls()
        return cls(str(data.get("kind", "bvh")), int(data.get("joints", 0)))


@dataclass(frozen=True)
class ImportReport:
    """``layout``: the file layout recognised (e.g. "Kinect joint positions, one row per frame");
    ``joints_found``: names in the file the import used; ``joints_unused``: names it could not use;
    ``warnings``: plain sentences (gaps bridged, joints estimated)."""

    kind: str
    layout: str
    joints_found: tuple[str, ...] = ()
    joints_unused: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True, eq=False)
class ImportedRecording:
    """A recording of any source as a `Motion` (skeleton and rotations) and what was found.

    ``lost_frames``: per joint the recorder lost in some frames (``"left_shoulder"``), a (F,)
    boolean over the motion's frames, True where it was lost (`analysis.sources.ik.lost_shoulders`);
    empty when none was (BVH files, landmark sources). The analysis leaves those frames out of
    that joint's clinical angles (`analysis.pipeline.analyse`'s ``lost_frames``)."""

    motion: Motion
    report: ImportReport
    lost_frames: Mapping[str, BoolArray] = field(default_factory=dict)

    @property
    def source(self) -> RecordingSource:
        return RecordingSource(self.report.kind, len(self.report.joints_found))
