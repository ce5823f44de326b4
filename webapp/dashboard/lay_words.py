"""A recording's result in the patient's words: what they did, what to change, what went well.

The therapist's page shows every key pose, level and clinical range; a patient gets only the
count of repetitions (all and done well: the run's reading, `webapp.recordings.reading`), the
one to three most important tips and the praise that concerns the body region the exercise
trains (issue 24: no praise for an ankle in a shoulder exercise).
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

from analysis.pipeline import AnalysisSummary
from webapp.exercises.models import Exercise
from webapp.recordings.models import RunReading
from webapp.recordings.reading import repetition_rows, to_correct
from webapp.recordings.words import body_part

MAX_TIPS = 3
# Words that place a body part in one region of the body; a sentence naming none is kept.
REGIONS = {
    "arms": ("shoulder", "arm", "elbow", "forearm", "wrist", "hand", "collarbone", "finger"),
    "legs": ("hip", "thigh", "knee", "leg", "ankle", "foot", "feet", "toe", "heel"),
    "trunk": ("trunk", "back", "spine", "chest", "neck", "head", "waist", "pelvis"),
}
_WORD = re.compile(r"[a-z]+")


@dataclass(frozen=True)
class LayResult:
    """What the patient's result page says (`fits` False: the recording did not show it)."""

    done: int
    done_well: int
    tips: tuple[str, ...] = ()
    went_well: tuple[str, ...] = ()
    fits: bool = True
    message: str = ""


def regions_of(text: str) -> set[str]:
    """The body regions a sentence or a body-part name speaks of ("left upper arm" → arms)."""
    words = set(_WORD.findall(text.lower()))
    found = set()
    for region, names in REGIONS.items():
        # "arms", "knees": a plural names the region as well as the singular
        if any(name in words or f"{name}s" in words for name in names):
            found.add(region)
    return found


def exercise_regions(exercise: Exercise | None, result: AnalysisSummary) -> set[str]:
    """The regions the exercise trains: its involved body parts, else what the tips correct."""
    joints: Iterable[str] = exercise.involved_joints if exercise is not None else ()
    regions: set[str] = set()
    for joint in joints or ():
        regions |= regions_of(body_part(str(joint)))
    if not regions:
        for correction in result.advice.corrections:
            regions |= regions_of(correction.part)
    return regions


def relevant_praise(sentences: Iterable[str], regions: set[str]) -> tuple[str, ...]:
    """The praise that names no region, or one the exercise trains (all of it when unknown)."""
    if not regions:
        return tuple(sentences)
    return tuple(s for s in sentences if not regions_of(s) or regions_of(s) & regions)


def lay_result(
    result: AnalysisSummary, exercise: Exercise | None, reading: RunReading | None = None
) -> LayResult:
    """The patient's summary of one finished analysis, as its run's ``reading`` says it (the
    therapist's verdicts first); a result without a run is read by the same rule, unlabelled."""
    if not result.match.fits:
        return LayResult(0, 0, fits=False, message=result.match.message)
    if reading is None:
        rows = repetition_rows(result, [], {})
        well, tips = sum(row["passed"] for row in rows), to_correct(result, rows)
    else:
        well, tips = reading.passed_count, reading.statements.get("to_correct", [])
    tips = tuple(tips[:MAX_TIPS])
    praise = relevant_praise(result.advice.went_well, exercise_regions(exercise, result))
    return LayResult(result.repetition_count, well, tips, praise)
