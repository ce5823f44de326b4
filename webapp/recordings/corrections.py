"""Therapist corrections of an analysed run: key poses (landmarks), per-joint assessment levels and
pass/fail verdicts per repetition. Each rebuilds the run's reading (`webapp.recordings.reading`):
a therapist's verdict is the verdict on every page, report and export. They are training data:
Celery beat rebuilds the exercise model from new landmark/level corrections and refits the 001
pass/fail threshold from the verdicts.

The payload (JSON), every part optional:

    {"landmarks": {"frames": [int, ...], "types": [int, ...]},
     "levels": [{"frame": int, "joint": str, "level": 1..4}, ...],
     "repetitions": [{"index": int, "passed": bool}, ...]}
"""

from __future__ import annotations

from typing import Any

from django.core.exceptions import ValidationError
from django.db import transaction

from webapp.accounts.models import User
from webapp.recordings.models import (
    AnalysisRun,
    AssessmentCorrection,
    LandmarkCorrection,
    RepetitionLabel,
)
from webapp.recordings.reading import build

MAX_LEVEL = 4


def _ints(values: Any, name: str) -> list[int]:
    if not isinstance(values, list) or not all(isinstance(v, int) for v in values):
        raise ValidationError({name: "Give a list of whole numbers."})
    return values


def check_landmarks(run: AnalysisRun, data: Any) -> tuple[list[int], list[int]]:
    if not isinstance(data, dict):
        raise ValidationError({"landmarks": "Give {'frames': [...], 'types': [...]}."})
    frames = _ints(data.get("frames"), "landmarks")
    types = _ints(data.get("types"), "landmarks")
    n_frames = run.recording.n_frames or (run.result.frames if run.result else 0)
    if len(frames) != len(types) or len(frames) < 2:
        raise ValidationError({"landmarks": "Give as many types as frames, at least two."})
    if frames != sorted(frames) or any(not 0 <= f < n_frames for f in frames):
        raise ValidationError({"landmarks": f"Frames must be in order, within 0..{n_frames - 1}."})
    if any(t < 1 for t in types):
        raise ValidationError({"landmarks": "Landmark types are numbers from 1."})
    return frames, types


def check_levels(run: AnalysisRun, data: Any) -> list[tuple[int, str, int]]:
    assessment = run.result.assessment if run.result else ()
    joints = {joint for item in assessment for joint in item.levels}
    if not isinstance(data, list):
        raise ValidationError({"levels": "Give a list of {'frame', 'joint', 'level'}."})
    out = []
    for item in data:
        frame, joint, level = (
            item.get(k) if isinstance(item, dict) else None for k in ("frame", "joint", "level")
        )
        if not isinstance(frame, int) or not isinstance(level, int):
            raise ValidationError({"levels": "Each correction needs a whole frame and level."})
        if joint not in joints:
            raise ValidationError({"levels": f"Unknown joint {joint!r}."})
        if not 1 <= level <= MAX_LEVEL:
            raise ValidationError(
                {"levels": f"Levels go from 1 (like the reference) to {MAX_LEVEL}."}
            )
        out.append((frame, joint, level))
    return out


def check_repetitions(run: AnalysisRun, data: Any) -> list[tuple[int, bool]]:
    count = run.result.repetition_count if run.result else 0
    if not isinstance(data, list):
        raise ValidationError({"repetitions": "Give a list of {'index', 'passed'}."})
    out = []
    for item in data:
        index = item.get("index") if isinstance(item, dict) else None
        passed = item.get("passed") if isinstance(item, dict) else None
        if not isinstance(index, int) or not 0 <= index < count or not isinstance(passed, bool):
            raise ValidationError(
                {"repetitions": f"Each verdict needs an index in 0..{count - 1} and passed."}
            )
        out.append((index, passed))
    return out


@transaction.atomic
def apply_corrections(run: AnalysisRun, data: Any, user: User) -> dict[str, int]:
    """Validate everything first, then store it; raises ValidationError naming the problem."""
    if not isinstance(data, dict) or not data.keys() & {"landmarks", "levels", "repetitions"}:
        raise ValidationError({"detail": "Give landmarks, levels or repetitions."})
    landmarks = check_landmarks(run, data["landmarks"]) if "landmarks" in data else None
    levels = check_levels(run, data.get("levels", []))
    verdicts = check_repetitions(run, data.get("repetitions", []))
    if landmarks is not None:
        LandmarkCorrection.objects.create(
            run=run, frames=landmarks[0], types=landmarks[1], author=user
        )
    for frame, joint, level in levels:
        AssessmentCorrection.objects.create(
            run=run, frame=frame, joint=joint, level=level, author=user
        )
    for index, passed in verdicts:
        RepetitionLabel.objects.update_or_create(
            run=run, index=index, defaults={"passed": passed, "author": user}
        )
    build(run)  # the run's one reading, with the therapist's verdicts, for every page and export
    return {
        "landmarks": int(landmarks is not None),
        "levels": len(levels),
        "repetitions": len(verdicts),
    }


def corrections_of(run: AnalysisRun) -> dict[str, Any]:
    latest = run.landmark_fixes.order_by("-created_at").first()
    return {
        "run": str(run.pk),
        "landmarks": {"frames": latest.frames, "types": latest.types} if latest else None,
        "levels": list(
            run.assessment_fixes.order_by("created_at").values("frame", "joint", "level")
        ),
        "repetitions": list(run.repetition_labels.order_by("index").values("index", "passed")),
    }
