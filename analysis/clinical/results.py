"""The clinical measures as a result stores them: an angle's range and one hand's workspace.

Made by this package (`analysis.clinical.angles`, `analysis.pipeline.clinical_stage`) and carried in
the pipeline's `AnalysisSummary` and `RepetitionResult` (`analysis.pipeline.results` re-exports
them), with their JSON form.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

JSON = dict[str, Any]


@dataclass(frozen=True)
class AngleRange:
    """The smallest and largest value of one anatomical angle over a stretch, and their span,
    in degrees (flexion and abduction positive, 0 in the anatomical standing pose)."""

    min: float
    max: float

    @property
    def range(self) -> float:
        return round(self.max - self.min, 2)

    def to_json(self) -> JSON:
        return {"min": self.min, "max": self.max, "range": self.range}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> AngleRange:
        return cls(float(data["min"]), float(data["max"]))


@dataclass(frozen=True)
class WorkspaceSummary:
    """One hand's reachable workspace as stored: the share of the frontal hemisphere around the
    shoulder its path covers (0..1), per quadrant (``upper_medial`` … 0..0.25 each), and a small
    hull of the covered patch for a 3D view (unit sphere, arm lengths; X anterior, Y superior,
    Z lateral), decimated to a few dozen vertices (`analysis.pipeline.clinical_stage`)."""

    side: str
    relative_area: float
    quadrants: Mapping[str, float] = field(default_factory=dict)
    vertices: tuple[tuple[float, float, float], ...] = ()
    faces: tuple[tuple[int, int, int], ...] = ()

    def to_json(self) -> JSON:
        return {
            "side": self.side,
            "relative_area": self.relative_area,
            "quadrants": dict(self.quadrants),
            "vertices": [list(v) for v in self.vertices],
            "faces": [list(f) for f in self.faces],
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> WorkspaceSummary:
        return cls(
            side=str(data.get("side", "")),
            relative_area=float(data.get("relative_area", 0.0)),
            quadrants={str(k): float(v) for k, v in (data.get("quadrants") or {}).items()},
            vertices=tuple(
                (float(x), float(y), float(z)) for x, y, z in data.get("vertices") or ()
            ),
            faces=tuple((int(a), int(b), int(c)) for a, b, c in data.get("faces") or ()),
        )
