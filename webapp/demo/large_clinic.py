"""Rows of a large synthetic clinic, for scale measurements (`manage.py fill_large_clinic`).

Summaries have the shape the analysis pipeline stores for an analysed recording (landmarks,
repetitions, score, per-joint assessment, feedback sentences, γ, range of motion, tempo, timings),
with about the same size (10–20 kB). No motion files are written: file fields name files that do
not exist, which the pages measured (lists, history, progress, dashboard) never open.

Everything is drawn from seeded generators so that a patient's recordings and runs can be
generated twice (once per table, streamed) without holding a million rows in memory.
"""

from __future__ import annotations

import datetime
import json
import random
import uuid
from collections.abc import Iterator
from dataclasses import dataclass

from analysis.feedback import Comment, LandmarkAssessment
from analysis.pipeline.results import AnalysisSummary, Guidance, KeyPose, RepetitionResult

JOINTS = (
    "Head",
    "LeftCollar",
    "LeftUpperArm",
    "RightForearm",
    "LeftUpperLeg",
    "LeftLowerLeg",
    "LeftFoot",
    "RightUpperLeg",
    "RightLowerLeg",
    "RightFoot",
)
JOINT_WORDS = dict(
    zip(
        JOINTS,
        (
            "head",
            "left collarbone",
            "left upper arm",
            "right forearm",
            "left thigh",
            "left lower leg",
            "left foot",
            "right thigh",
            "right lower leg",
            "right foot",
        ),
        strict=True,
    )
)
POSES = {1: "the start", 2: "the key pose 2"}
OPENERS = ("This time, ", "Now, ", "On this occasion, ", "Again, ", "")
DEGREES = ("slightly", "noticeably", "very")
FIRST_NAMES = ("Alex", "Sam", "Robin", "Kim", "Jo", "Noa", "Eli", "Mia", "Lou", "Ira", "Ada")
LAST_NAMES = ("Berg", "Costa", "Dahl", "Evans", "Fischer", "Garcia", "Hansen", "Ivanova", "Jung")
DAYS_OF_HISTORY = 730
REP_FRAMES = 85


def new_uuid(rng: random.Random) -> uuid.UUID:
    return uuid.UUID(int=rng.getrandbits(128), version=4)


def feedback_sentence(rng: random.Random, pose: int) -> str:
    joints = rng.sample(JOINTS, rng.randint(1, 4))
    where = POSES[pose]
    parts = [
        f"at {where}, your {JOINT_WORDS[j]} moved {rng.choice(DEGREES)} differently "
        "from the demonstration."
        for j in joints
    ]
    tips = [
        f"Look at the instructor's {JOINT_WORDS[j]} at {where} and try to match it." for j in joints
    ]
    return rng.choice(OPENERS) + " And ".join(parts) + " " + " ".join(tips)


def repetitions(rng: random.Random, count: int) -> tuple[RepetitionResult, ...]:
    reps = []
    for index in range(count):
        start = 15 + index * REP_FRAMES
        end = start + REP_FRAMES - 1
        said = rng.choice(("", "", "too fast", "incomplete"))
        reps.append(
            RepetitionResult(
                start=start,
                end=end,
                peak=start + REP_FRAMES // 2,
                score=round(rng.uniform(35, 98), 2),
                deviation=round(rng.uniform(0.005, 0.05), 5),
                reach=round(rng.uniform(0.7, 1.3), 3),
                tempo=round(rng.uniform(0.7, 1.5), 3),
                guidance=(Guidance(said, (start, end)),) if said else (),
            )
        )
    return tuple(reps)


def summary_without_score(rng: random.Random) -> dict:
    """One analysed recording's summary (all fields but `score`), written by the typed result
    (`AnalysisSummary.to_json`) so it has the stored shape whatever that becomes."""
    count = rng.randint(6, 12)
    landmarks = tuple(KeyPose(15 + i * REP_FRAMES // 2, 1 + i % 2) for i in range(2 * count + 1))
    assessment = tuple(
        LandmarkAssessment(
            mark.frame, mark.type, {j: rng.choice((1, 1, 1, 2, 2, 3, 4)) for j in JOINTS}
        )
        for mark in landmarks
    )
    feedback = tuple(
        Comment(mark.frame, feedback_sentence(rng, mark.type))
        for mark in landmarks
        if rng.random() < 0.85
    )
    summary = AnalysisSummary(
        frames=30 + count * REP_FRAMES,
        fps=30.0003,
        landmarks=landmarks,
        repetitions=repetitions(rng, count),
        score=None,
        assessment=assessment,
        feedback=feedback,
        gamma={j: round(rng.uniform(0.2, 1.0), 4) for j in JOINTS},
        mirrored=rng.random() < 0.1,
        range_of_motion={j: round(rng.uniform(10, 120), 2) for j in JOINTS},
        tempo=round(rng.uniform(0.8, 1.5), 3),
        timings_ms={
            stage: round(rng.uniform(1, 130), 3)
            for stage in ("prepare", "repetitions", "scores", "assessment", "feedback", "playback")
        },
    )
    data = summary.to_json()
    del data["score"]  # each run writes its own (`summary_tails`)
    return data


def summary_tails(seed: int, count: int = 256) -> list[str]:
    """JSON texts of summaries without the opening brace and `score`: ``"frames": ..., }``.

    A run's summary is ``{"score": S, `` + one of these, so each run gets its own score (the
    progress chart's line) while the generator pays for `json.dumps` only `count` times.
    """
    rng = random.Random(seed)
    return [json.dumps(summary_without_score(rng))[1:] for _ in range(count)]


@dataclass(frozen=True)
class Upload:
    """One recording of a patient with its runs' statuses (oldest first)."""

    recording: uuid.UUID
    exercise: int  # index into the clinic's exercises
    at: datetime.datetime
    runs: tuple[tuple[uuid.UUID, str], ...]
    score: float


def runs_per_patient(total_runs: int, patients: int, seed: int) -> list[int]:
    """Uneven counts (a few patients with many runs) that add up to `total_runs`."""
    rng = random.Random(seed)
    weights = [rng.lognormvariate(0, 0.8) for _ in range(patients)]
    scale = total_runs / sum(weights)
    counts = [max(1, int(w * scale)) for w in weights]
    index = 0
    while sum(counts) != total_runs:  # spread the rounding error one run at a time
        step = 1 if sum(counts) < total_runs else -1
        if counts[index % patients] + step >= 1:
            counts[index % patients] += step
        index += 1
    return counts


def run_statuses(rng: random.Random, remaining: int) -> tuple[str, ...]:
    """Most recordings have one succeeded run; some failed; some were re-analysed."""
    draw = rng.random()
    if remaining >= 2 and draw < 0.05:
        return ("failed", "succeeded")
    if draw < 0.07:
        return ("failed",)
    return ("succeeded",)


def patient_uploads(
    seed: int, patient_index: int, run_count: int, exercises: int, now: datetime.datetime
) -> Iterator[Upload]:
    """The recordings of one patient, oldest first; the same for the same arguments."""
    rng = random.Random(seed * 1_000_003 + patient_index)
    statuses = []
    remaining = run_count
    while remaining > 0:
        statuses.append(run_statuses(rng, remaining))
        remaining -= len(statuses[-1])
    offsets = sorted(rng.uniform(0, DAYS_OF_HISTORY) for _ in statuses)
    base, trend = rng.uniform(40, 70), rng.uniform(0, 25)
    for index, (offset, kinds) in enumerate(zip(offsets, statuses, strict=True)):
        progress = index / max(1, len(statuses) - 1)
        yield Upload(
            recording=new_uuid(rng),
            exercise=rng.randrange(exercises),
            at=now - datetime.timedelta(days=DAYS_OF_HISTORY - offset),
            runs=tuple((new_uuid(rng), kind) for kind in kinds),
            score=round(min(99.0, base + trend * progress + rng.gauss(0, 6)), 2),
        )


def patient_name(rng: random.Random, index: int) -> str:
    return f"{rng.choice(FIRST_NAMES)} {rng.choice(LAST_NAMES)} {index:05d}"
