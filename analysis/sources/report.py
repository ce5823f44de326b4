"""What an importer found in a capture file, and the short source record a result keeps."""

from __future__ import annotations

from dataclasses import dataclass

from analysis.bvh.io import Motion

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
    """A recording of any source as a `Motion` (skeleton and rotations) and what was found."""

    motion: Motion
    report: ImportReport

    @property
    def source(self) -> RecordingSource:
        return RecordingSource(self.report.kind, len(self.report.joints_found))
