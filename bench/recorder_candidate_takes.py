"""UI-PRMD's paired takes and development sessions, prepared once for
`bench.eval_recorder_candidates` (issue 35, item 2): each exercise's tutors (made from s03's
Kinect session and from s01's Vicon take), the Kinect and Vicon side of every paired take in the
tutor's joint order and rate, cut at the data set's labelled repetition starts, and the
development sessions (s02–s07, correct and incorrect) against s01's Kinect session.
"""

from __future__ import annotations

import csv
import itertools
import pickle
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion, read
from analysis.clinical.body import Body, find_body
from analysis.kinematics import scaled_positions
from analysis.pipeline.model_fit import SCORING_FPS, tutor_repetitions
from analysis.pipeline.prepare import prepare
from bench.eval_recorders import DATA, marks, vicon_key_poses, vicon_motion, vicon_rows

FloatArray = npt.NDArray[np.float64]
SUBJECTS = [f"s{k:02d}" for k in range(2, 8)]


@dataclass
class Tutor:
    points: FloatArray  # (F, J, 3) scaled positions, every joint
    reps: list[tuple[int, int]]
    step: int
    fps: float
    body: Body
    motion: Motion
    recorder: str = "kinect"


@dataclass
class Take:
    points: FloatArray  # (F, J, 3) in the tutor's joint order, at its rate
    repetitions: list[tuple[int, int]]
    recorder: str = "kinect"


def tutor(motion: Motion, frames: list[int], types: list[int], recorder: str = "kinect") -> Tutor:
    points = scaled_positions(motion, list(range(len(motion.skeleton.names))))
    step = max(1, round(motion.fps / SCORING_FPS))
    reps = tutor_repetitions(frames, types)
    return Tutor(points, reps, step, motion.fps, find_body(motion.skeleton), motion, recorder)


def take(motion: Motion, model: Tutor, starts: list[int], recorder: str = "kinect") -> Take:
    prepared = prepare(motion, model.motion.skeleton, model.fps, 1.0)
    ratio = model.fps / motion.fps
    bounds = [round(f * ratio) for f in starts] + [prepared.n_frames]
    reps = [(a, b - 1) for a, b in itertools.pairwise(bounds)]
    return Take(prepared.points, reps, recorder)


def starts_of(text: str) -> list[int]:
    return [int(v) for v in text.split(";")]


@dataclass
class Loaded:
    """One exercise's tutors and takes, prepared once for every candidate."""

    models: dict[str, Tutor]  # what the exercise was made from: its tutor
    paired: dict[str, list[tuple[Take, Take]]]  # per tutor: (Kinect take, Vicon take)
    dev: Tutor
    names: list[str]
    sessions: list[Take]


def load(exercise: str, cache: Path | None = None) -> Loaded:
    """`prepared` for ``exercise``, kept in ``cache`` (a pickle per exercise) when given."""
    kept = cache / f"{exercise}.pickle" if cache is not None else None
    if kept is not None and kept.exists():
        with open(kept, "rb") as handle:
            found: Loaded = pickle.load(handle)
        return found
    found = prepared(exercise)
    if kept is not None:
        kept.parent.mkdir(parents=True, exist_ok=True)
        with open(kept, "wb") as handle:
            pickle.dump(found, handle)
    return found


def prepared(exercise: str) -> Loaded:
    """Reads and prepares ``exercise``'s tutors and takes (about 10 s each)."""
    with open(DATA / "labels.csv") as handle:
        labels = {r["file"]: starts_of(r["rep_start_frames"]) for r in csv.DictReader(handle)}
    kinect_name = f"sessions/{exercise}_s03_correct.bvh.gz"
    models = {
        "kinect": tutor(read(DATA / kinect_name), *marks()[kinect_name]),
        "vicon": tutor(*vicon_key_poses(exercise), recorder="vicon"),
    }
    paired: dict[str, list[tuple[Take, Take]]] = {"kinect": [], "vicon": []}
    for name, row in sorted(vicon_rows().items()):
        if row["exercise"] != exercise:
            continue
        kinect, vicon = read(DATA / row["kinect_session"]), vicon_motion(row["file"])
        for made_from, model in models.items():
            if made_from == "vicon" and name == f"{exercise}_s01_correct":
                continue  # the take the exercise was made from
            paired[made_from].append((
                take(kinect, model, labels[row["kinect_session"]]),
                take(vicon, model, starts_of(row["rep_start_frames"]), "vicon"),
            ))  # fmt: skip
    dev_name = f"sessions/{exercise}_s01_correct.bvh.gz"
    dev = tutor(read(DATA / dev_name), *marks()[dev_name])
    names = [
        f"sessions/{exercise}_{s}_{lab}.bvh.gz"
        for s in SUBJECTS
        for lab in ("correct", "incorrect")
    ]
    sessions = [take(read(DATA / n), dev, labels[n]) for n in names]
    return Loaded(models, paired, dev, names, sessions)
