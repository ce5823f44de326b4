"""The timeline of one analysed recording, in plain words and seconds, for the page and the PDF.

Three key-pose layers (found by the classifier, moved or chosen by refining, removed or added by
periodic landmark sequence analysis, each labelled in a therapist's words), the repetitions with
the verdicts of the run's reading (`webapp.recordings.reading`), and the guidance of each
repetition with the stretch it applies to.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from analysis.pipeline import AnalysisSummary
from webapp.recordings.models import RunReading
from webapp.recordings.reading import guidance_words, repetition_rows
from webapp.recordings.words import key_pose_name

LAYERS = (
    ("identified", "key poses recognised directly"),
    ("refined", "key poses adjusted to the nearest clear position"),
    ("periodic", "key poses removed or added so they come in the exercise's order"),
)
FALLBACK_NOTE = (
    "The key poses did not form a repeating cycle, so the repetitions were cut from the "
    "movement's main direction instead."
)


def seconds(frame: int, fps: float) -> float:
    return round(frame / fps, 2) if fps > 0 else float(frame)


class _Scale:
    def __init__(self, frames: int, fps: float) -> None:
        self.frames, self.fps = max(frames, 1), fps

    def at(self, frame: int) -> float:
        """Position along the timeline, percent."""
        return round(100.0 * min(max(frame, 0), self.frames - 1) / max(self.frames - 1, 1), 3)

    def mark(self, frame: int, **extra: Any) -> dict[str, Any]:
        return {
            "frame": frame,
            "seconds": seconds(frame, self.fps),
            "left": self.at(frame),
            **extra,
        }

    def span(self, first: int, last: int, **extra: Any) -> dict[str, Any]:
        return {
            "first": first,
            "last": last,
            "first_s": seconds(first, self.fps),
            "last_s": seconds(last, self.fps),
            "left": self.at(first),
            "width": max(round(self.at(last) - self.at(first), 3), 0.6),
            **extra,
        }


def ticks(scale: _Scale) -> list[dict[str, Any]]:
    """Round times along the axis (about eight), seconds and percent."""
    duration = (scale.frames - 1) / scale.fps if scale.fps > 0 else 0.0
    if duration <= 0:
        return []
    raw = duration / 8
    power = 10 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1, 2, 5, 10) if m * power >= raw)
    return [
        {
            "seconds": round(k * step, 3),
            "label": f"{round(k * step, 3):g}",
            "left": round(100.0 * k * step / duration, 3),
        }
        for k in range(int(duration / step + 1e-9) + 1)
    ]


def repetitions(
    result: AnalysisSummary, scale: _Scale, reading: RunReading | None
) -> list[dict[str, Any]]:
    """Each repetition's stretch with the reading's verdict (a result without a run: the same
    rule without therapist labels)."""
    rows = reading.repetitions if reading is not None else repetition_rows(result, [], {})
    out = []
    for rep, row in zip(result.repetitions, rows, strict=True):
        guidance = [
            scale.span(*g.frames, label=guidance_words(g.type), number=row["number"])
            for g in rep.guidance
        ]
        out.append(
            scale.span(
                rep.start, rep.end, number=row["number"], score=row["shown_score"],
                passed=row["passed"], verdict=row["verdict"], reasons=row["reasons"],
                guidance=guidance,
            )
        )  # fmt: skip
    return out


def timeline(
    result: AnalysisSummary,
    type_names: Mapping[str, str],
    stored: Mapping[str, Any] | None = None,
    fallback_frames: int = 0,
    reading: RunReading | None = None,
) -> dict[str, Any]:
    """Everything the timeline shows; verdicts are the run's ``reading``'s. ``stored`` (the
    run's raw summary) is no longer read: the typed result tells a run that stored no
    segmentation apart (None)."""
    scale = _Scale(result.frames or fallback_frames, result.fps)

    def pose(mark: Any) -> dict[str, Any]:
        name = key_pose_name(mark.type, type_names)
        return scale.mark(mark.frame, name=name, type=mark.type)

    by_origin = {
        origin: [pose(m) for m in result.landmarks if m.origin == origin]
        for origin in ("identified", "refined", "inserted")
    }
    inserted_frames = {m["frame"] for m in by_origin["inserted"]}
    inserted = by_origin["inserted"] + [
        scale.mark(f, name="added key pose", type=0)
        for f in result.periodic.inserted
        if f not in inserted_frames
    ]
    return {
        "frames": scale.frames,
        "fps": result.fps,
        "duration_s": seconds(scale.frames - 1, result.fps),
        "layers": [{"key": key, "label": label} for key, label in LAYERS],
        "identified": by_origin["identified"],
        "refined": by_origin["refined"],
        "removed": [
            scale.mark(f, name="removed key pose", type=0) for f in result.periodic.removed
        ],
        "inserted": inserted,
        "candidates": result.periodic.candidates,
        "ticks": ticks(scale),
        "threshold": round(result.pass_threshold),
        "repetitions": repetitions(result, scale, reading),
        # Older runs stored no segmentation (None): only an explicit "fallback" earns the note;
        # a recording that does not show the exercise has no repetition to explain.
        "fallback": result.segmentation == "fallback" and result.match.fits,
        "fallback_note": FALLBACK_NOTE,
    }
