"""Typed results of the pipeline's stages, and their JSON form at the boundary.

Every stage of `analysis.pipeline.run` returns one of these frozen objects; `AnalysisSummary`
gathers them for one recording. ``to_json`` gives the fields of ``analyse --json`` (CONTRACTS.md)
and ``from_json`` reads them back (tolerating fields that older runs did not store), so the web
app and the workers read a stored result through these classes, never by string key.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from analysis.feedback import Comment, LandmarkAssessment

JSON = dict[str, Any]


@dataclass(frozen=True)
class KeyPose:
    """A landmark of the recording: its frame and the tutor's key-pose type (1 starts a rep)."""

    frame: int
    type: int

    def to_json(self) -> JSON:
        return {"frame": self.frame, "type": self.type}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> KeyPose:
        return cls(int(data["frame"]), int(data["type"]))


@dataclass(frozen=True)
class RepetitionResult:
    """One repetition: frames (start, end-of-range peak, end), score 0–100, its distance to the
    tutor, how far along the tutor's movement it went (reach, 1 = as far), its duration over the
    tutor's (tempo) and the main guidance ("" when none)."""

    start: int
    end: int
    peak: int
    score: float
    deviation: float = 0.0
    reach: float = 0.0
    tempo: float = 1.0
    guidance: str = ""

    def to_json(self) -> JSON:
        return {
            "start": self.start, "end": self.end, "peak": self.peak, "score": self.score,
            "deviation": self.deviation, "reach": self.reach, "tempo": self.tempo,
            "guidance": self.guidance,
        }  # fmt: skip

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RepetitionResult:
        guidance = data.get("guidance") or ""
        return cls(
            start=int(data["start"]),
            end=int(data["end"]),
            peak=int(data.get("peak", data["start"])),
            score=float(data["score"]),
            deviation=float(data.get("deviation", 0.0)),
            reach=float(data.get("reach", 0.0)),
            tempo=float(data.get("tempo", 1.0)),
            guidance=guidance if isinstance(guidance, str) else "",
        )


def assessment_to_json(item: LandmarkAssessment) -> JSON:
    return {"frame": item.frame, "type": item.type, "levels": dict(item.levels)}


def comment_from_json(data: Mapping[str, Any]) -> Comment:
    return Comment(int(data.get("frame", 0)), str(data.get("text", "")), str(data.get("tip", "")))


@dataclass(frozen=True)
class AnalysisSummary:
    """Everything the therapist reads about one recording (the ``analyse --json`` object)."""

    frames: int
    fps: float
    landmarks: tuple[KeyPose, ...]
    repetitions: tuple[RepetitionResult, ...]
    score: float
    assessment: tuple[LandmarkAssessment, ...] = ()
    feedback: tuple[Comment, ...] = ()
    gamma: Mapping[str, float] = field(default_factory=dict)
    mirrored: bool = False
    range_of_motion: Mapping[str, float] = field(default_factory=dict)
    tempo: float | None = None
    timings_ms: Mapping[str, float] = field(default_factory=dict)

    @property
    def repetition_count(self) -> int:
        return len(self.repetitions)

    def levels_by_joint(self) -> dict[str, list[int]]:
        """Every assessed level of each joint, in landmark order."""
        out: dict[str, list[int]] = {}
        for item in self.assessment:
            for joint, level in item.levels.items():
                out.setdefault(joint, []).append(level)
        return out

    def to_json(self) -> JSON:
        return {
            "frames": self.frames,
            "fps": self.fps,
            "landmarks": [m.to_json() for m in self.landmarks],
            "repetitions": [r.to_json() for r in self.repetitions],
            "score": self.score,
            "assessment": [assessment_to_json(a) for a in self.assessment],
            "feedback": [c.to_dict() for c in self.feedback],
            "gamma": dict(self.gamma),
            "mirrored": self.mirrored,
            "range_of_motion": dict(self.range_of_motion),
            "tempo": self.tempo,
            "repetition_count": self.repetition_count,
            "timings_ms": dict(self.timings_ms),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> AnalysisSummary:
        """Read a stored summary; fields a run did not store take their empty value."""
        tempo = data.get("tempo")
        return cls(
            frames=int(data.get("frames", 0)),
            fps=float(data.get("fps", 0.0)),
            landmarks=tuple(KeyPose.from_json(m) for m in data.get("landmarks", ())),
            repetitions=tuple(RepetitionResult.from_json(r) for r in data.get("repetitions", ())),
            score=float(data.get("score", 0.0)),
            assessment=tuple(LandmarkAssessment.from_dict(a) for a in data.get("assessment", ())),
            feedback=tuple(comment_from_json(c) for c in data.get("feedback", ())),
            gamma={str(k): float(v) for k, v in (data.get("gamma") or {}).items()},
            mirrored=bool(data.get("mirrored", False)),
            range_of_motion={
                str(k): float(v) for k, v in (data.get("range_of_motion") or {}).items()
            },
            tempo=None if tempo is None else float(tempo),
            timings_ms={str(k): float(v) for k, v in (data.get("timings_ms") or {}).items()},
        )
