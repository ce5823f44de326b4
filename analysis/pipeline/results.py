"""Typed results of the pipeline's stages, and their JSON form at the boundary.

Every stage of `analysis.pipeline.run` returns one of these frozen objects; `AnalysisSummary`
gathers them for one recording. ``to_json`` gives the fields of ``analyse --json`` (the interface
contract)
and ``from_json`` reads them back (tolerating fields that older runs did not store), so the web
app and the workers read a stored result through these classes, never by string key.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from analysis.clinical.results import AngleRange, WorkspaceSummary
from analysis.feedback import Comment, LandmarkAssessment
from analysis.feedback.advice import Advice
from analysis.sources.report import RecordingSource

JSON = dict[str, Any]


@dataclass(frozen=True)
class KeyPose:
    """A landmark of the recording: its frame, the tutor's key-pose type (1 starts a rep) and
    where it comes from: "identified" (the classifier's frame as is), "refined" (chosen among
    candidates or moved by refining) or "inserted" (added to complete the cycle)."""

    frame: int
    type: int
    origin: str = "identified"

    def to_json(self) -> JSON:
        return {"frame": self.frame, "type": self.type, "origin": self.origin}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> KeyPose:
        return cls(int(data["frame"]), int(data["type"]), str(data.get("origin", "identified")))


@dataclass(frozen=True)
class Guidance:
    """One piece of paper 001's guidance ("too fast", "too slow", "overdone", "incomplete") with
    the first and last frame of the recording where it happens."""

    type: str
    frames: tuple[int, int]

    def to_json(self) -> JSON:
        return {"type": self.type, "frames": list(self.frames)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Guidance:
        first, last = data["frames"]
        return cls(str(data["type"]), (int(first), int(last)))


@dataclass(frozen=True)
class PeriodicSummary:
    """What periodic landmark sequence analysis worked on: the number of candidate landmarks,
    and the frames of the key poses it removed and of those inserted to complete the cycle."""

    candidates: int = 0
    removed: tuple[int, ...] = ()
    inserted: tuple[int, ...] = ()

    def to_json(self) -> JSON:
        return {
            "candidates": self.candidates,
            "removed": list(self.removed),
            "inserted": list(self.inserted),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> PeriodicSummary:
        return cls(
            int(data.get("candidates", 0)),
            tuple(int(f) for f in data.get("removed", ())),
            tuple(int(f) for f in data.get("inserted", ())),
        )


@dataclass(frozen=True)
class RepetitionResult:
    """One repetition: frames (start, end-of-range peak, end), score 0–100 and whether it passed
    the exercise's threshold, its distance to the tutor, how far along the tutor's movement it
    went (reach, 1 = as far), its duration over the tutor's (tempo), paper 001's guidance with
    the frames where each applies and its GB-DTW score, and paper 003's alignment quality
    (Kendall τ, −1..1) and similarity (mean angular distance to the tutor, degrees)."""

    start: int
    end: int
    peak: int
    score: float
    deviation: float = 0.0
    reach: float = 0.0
    tempo: float = 1.0
    guidance: tuple[Guidance, ...] = ()
    passed: bool | None = True  # None: a run stored before verdicts (judge by the score)
    gbdtw_score: float | None = None
    alignment_tau: float | None = None
    similarity: float | None = None
    # anatomical name -> its range over this repetition (degrees, 0.1°); empty in older runs
    clinical_angles: Mapping[str, AngleRange] = field(default_factory=dict)
    # paper 001's reach: the involved joints' angular excursion over the tutor's (1 = as far);
    # with tempo, what a later session's pace is judged against (None in older runs)
    excursion: float | None = None
    # the sentences the patient reads for this repetition (`analysis.pipeline.judgement`): never
    # empty when it failed; empty in runs stored before them
    reasons: tuple[str, ...] = ()

    @property
    def main_guidance(self) -> str:
        """The most pressing guidance type, "" when there is none."""
        return self.guidance[0].type if self.guidance else ""

    def analysis_verdict(self, pass_threshold: float) -> bool:
        """Whether the analysis passed it: its stored verdict, or for a run stored before
        verdicts were kept, its score against that run's pass threshold (the one place the
        rule for old runs lives; the web side's reading asks here)."""
        return bool(self.passed) if self.passed is not None else self.score >= pass_threshold

    def to_json(self) -> JSON:
        return {
            "start": self.start, "end": self.end, "peak": self.peak, "score": self.score,
            "passed": self.passed, "deviation": self.deviation, "reach": self.reach,
            "tempo": self.tempo, "guidance": [g.to_json() for g in self.guidance],
            "gbdtw_score": self.gbdtw_score, "alignment_tau": self.alignment_tau,
            "similarity": self.similarity, "excursion": self.excursion,
            "reasons": list(self.reasons), **_angles_json(self.clinical_angles),
        }  # fmt: skip

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RepetitionResult:
        return cls(
            start=int(data["start"]),
            end=int(data["end"]),
            peak=int(data.get("peak", data["start"])),
            score=float(data["score"]),
            deviation=float(data.get("deviation", 0.0)),
            reach=float(data.get("reach", 0.0)),
            tempo=float(data.get("tempo", 1.0)),
            guidance=_guidance_from_json(data),
            passed=_optional_bool(data.get("passed")),
            gbdtw_score=_optional_float(data.get("gbdtw_score")),
            alignment_tau=_optional_float(data.get("alignment_tau")),
            similarity=_optional_float(data.get("similarity")),
            clinical_angles=_angles_from_json(data.get("clinical_angles")),
            excursion=_optional_float(data.get("excursion")),
            reasons=tuple(str(t) for t in data.get("reasons") or ()),
        )


def _angles_json(angles: Mapping[str, AngleRange]) -> JSON:
    """A repetition's ``clinical_angles`` as ``{name: [min, max]}`` (degrees; the range is their
    difference), left out when it has none (older runs): ten repetitions stay a few kB."""
    if not angles:
        return {}
    return {"clinical_angles": {k: [v.min, v.max] for k, v in angles.items()}}


def _angles_from_json(data: Mapping[str, Any] | None) -> dict[str, AngleRange]:
    """Reads ``[min, max]`` pairs, or ``{"min", "max"}`` objects as the recording's are."""
    out = {}
    for name, value in (data or {}).items():
        if isinstance(value, Mapping):
            out[str(name)] = AngleRange.from_json(value)
        else:
            out[str(name)] = AngleRange(float(value[0]), float(value[1]))
    return out


def _optional_float(value: Any) -> float | None:
    return None if value is None else float(value)


def _optional_bool(value: Any) -> bool | None:
    return None if value is None else bool(value)


def _optional_str(value: Any) -> str | None:
    return None if value is None else str(value)


def _guidance_from_json(data: Mapping[str, Any]) -> tuple[Guidance, ...]:
    """Guidance items; runs stored before they had frames kept one type for the repetition."""
    stored = data.get("guidance") or ()
    if isinstance(stored, str):
        return (Guidance(stored, (int(data["start"]), int(data["end"]))),)
    return tuple(Guidance.from_json(g) for g in stored)


@dataclass(frozen=True)
class ExerciseMatch:
    """Whether the recording shows the exercise (`analysis.pipeline.match`): when it does not,
    a plain ``message`` and the id of the clinic's exercise it ``looks_like`` (None if none)."""

    fits: bool = True
    message: str = ""
    looks_like: str | None = None

    def to_json(self) -> JSON:
        if self.fits:
            return {"fits": True}
        return {"fits": False, "message": self.message, "looks_like": self.looks_like}

    @classmethod
    def from_json(cls, data: Mapping[str, Any] | None) -> ExerciseMatch:
        """Runs stored before the check always fitted."""
        if not data or data.get("fits", True):
            return cls()
        other = data.get("looks_like")
        return cls(False, str(data.get("message", "")), None if other is None else str(other))


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
    score: float | None  # None when the recording does not fit the exercise (``match``)
    assessment: tuple[LandmarkAssessment, ...] = ()
    feedback: tuple[Comment, ...] = ()
    gamma: Mapping[str, float] = field(default_factory=dict)
    mirrored: bool = False
    range_of_motion: Mapping[str, float] = field(default_factory=dict)
    tempo: float | None = None
    timings_ms: Mapping[str, float] = field(default_factory=dict)
    # "fallback": cut on the progress axis (no key-pose cycle); None: a run stored before it
    segmentation: str | None = "landmarks"
    periodic: PeriodicSummary = field(default_factory=PeriodicSummary)
    pass_threshold: float = 70.0  # on the 0–100 scale; the same on every exercise since issue 17
    # anatomical name (the interface contract, e.g. "knee_flexion_left") -> its range over the
    # recording
    clinical_angles: Mapping[str, AngleRange] = field(default_factory=dict)
    # "left" / "right" -> reachable workspace of that hand; only for exercises of the arms
    workspace: Mapping[str, WorkspaceSummary] = field(default_factory=dict)
    # every angle name absent from clinical_angles -> why it is not a measurement (plain words:
    # a segment the capture lacks, or readings beyond the body's limits); empty in older runs
    clinical_notes: Mapping[str, str] = field(default_factory=dict)
    # the few most important corrections and what went well; empty in runs stored before
    advice: Advice = field(default_factory=Advice)
    # whether the recording shows the exercise at all; runs stored before always fitted
    match: ExerciseMatch = field(default_factory=ExerciseMatch)
    # the kind of capture file and how many of its joints were used; runs stored before: BVH
    source: RecordingSource = field(default_factory=RecordingSource)

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
            "segmentation": self.segmentation,
            "periodic": self.periodic.to_json(),
            "pass_threshold": self.pass_threshold,
            "clinical_angles": {k: v.to_json() for k, v in self.clinical_angles.items()},
            "clinical_notes": dict(self.clinical_notes),
            "workspace": {k: v.to_json() for k, v in self.workspace.items()},
            "advice": self.advice.to_json(),
            "match": self.match.to_json(),
            "source": self.source.to_json(),
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
            score=_optional_float(data.get("score", 0.0)),
            assessment=tuple(LandmarkAssessment.from_dict(a) for a in data.get("assessment", ())),
            feedback=tuple(comment_from_json(c) for c in data.get("feedback", ())),
            gamma={str(k): float(v) for k, v in (data.get("gamma") or {}).items()},
            mirrored=bool(data.get("mirrored", False)),
            range_of_motion={
                str(k): float(v) for k, v in (data.get("range_of_motion") or {}).items()
            },
            tempo=None if tempo is None else float(tempo),
            timings_ms={str(k): float(v) for k, v in (data.get("timings_ms") or {}).items()},
            segmentation=_optional_str(data.get("segmentation")),
            periodic=PeriodicSummary.from_json(data.get("periodic") or {}),
            pass_threshold=float(data.get("pass_threshold", 50.0)),
            clinical_angles={
                str(k): AngleRange.from_json(v)
                for k, v in (data.get("clinical_angles") or {}).items()
            },
            workspace={
                str(k): WorkspaceSummary.from_json(v)
                for k, v in (data.get("workspace") or {}).items()
            },
            clinical_notes={str(k): str(v) for k, v in (data.get("clinical_notes") or {}).items()},
            advice=Advice.from_json(data.get("advice")),
            match=ExerciseMatch.from_json(data.get("match")),
            source=RecordingSource.from_json(data.get("source")),
        )


@dataclass(frozen=True)
class JsonShape:
    """Where a result class's ``to_json`` differs from its fields: keys it adds (with their type),
    fields it leaves out, keys it writes only sometimes, and fields it writes in another type. The
    API's OpenAPI schema is generated from the fields and these (`webapp.api.result_schema`), so
    a change to ``to_json`` that is not declared here fails the schema tests."""

    added: Mapping[str, Any] = field(default_factory=dict)
    left_out: tuple[str, ...] = ()
    optional: tuple[str, ...] = ()
    written_as: Mapping[str, Any] = field(default_factory=dict)


JSON_SHAPES: Mapping[type, JsonShape] = {
    AnalysisSummary: JsonShape(added={"repetition_count": int}),
    # a repetition's angles as [min, max] pairs, and only when it has some (older runs)
    RepetitionResult: JsonShape(
        optional=("clinical_angles",),
        written_as={"clinical_angles": Mapping[str, tuple[float, float]]},
    ),
    AngleRange: JsonShape(added={"range": float}),
    ExerciseMatch: JsonShape(optional=("message", "looks_like")),  # only when it does not fit
    Comment: JsonShape(left_out=("feedback",)),
}
