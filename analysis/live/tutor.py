"""What every live session of an exercise model reads of its tutor, made once per model: the
tutor repetition the stream is aligned with (its features, the joint weights) and the pace rule's
reference (`analysis.live.aligner.LiveAligner` reads it at each session's set-up)."""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from analysis.kinematics import quaternions as quat
from analysis.online.frames import FrameKinematics
from analysis.pipeline.gestures import reference_excursion
from analysis.pipeline.model import FittedModel

FloatArray = npt.NDArray[np.float64]
IndexArray = npt.NDArray[np.intp]


class Tutor(NamedTuple):
    """What every session of a model reads of its tutor: made once per model (a session's
    set-up was mostly this, the reference excursion's alignments above all), read-only."""

    joints: IndexArray  # the aligned joints (model order)
    start: int  # the tutor repetition the stream is aligned with
    end: int
    q: FloatArray  # (m, d) its features
    weights: tuple[float, ...] | None  # the model's joint weights of the aligned joints
    reference: FloatArray  # the pace rule's reference excursion
    reference_frames: float  # the tutor's median repetition length


_TUTORS: weakref.WeakKeyDictionary[FittedModel, Tutor] = weakref.WeakKeyDictionary()


def tutor_of(model: FittedModel) -> Tutor:
    """The model's `Tutor`, made at its first session."""
    made = _TUTORS.get(model)
    if made is None:
        made = _TUTORS[model] = _made(model)
    return made


def _made(model: FittedModel) -> Tutor:
    parts = model.components
    joints = [j for j in parts.involved_index if j != 0] or list(parts.involved_index)
    index = np.asarray(joints, dtype=np.intp)
    a, b = parts.tutor_reps[0] if parts.tutor_reps else (0, model.tutor.n_frames - 1)
    tutor = FrameKinematics(model.tutor.skeleton).rotations(model.tutor.frames)
    q = quat.make_continuous(tutor[a : b + 1][:, index]).reshape(b - a + 1, -1)
    weights = getattr(parts, "joint_weights", None)
    chosen = None if weights is None else tuple(np.asarray(weights)[index])
    reps, papers = parts.tutor_reps or [(a, b)], parts.papers
    mirror_q = tutor[:, [parts.mirror[j] for j in papers.joint_index]]
    reference = reference_excursion(papers.tutor_q, mirror_q, reps, parts.scoring_step)
    frames = float(np.median([e - s + 1 for s, e in reps]))
    for array in (index, q, reference):
        array.setflags(write=False)
    return Tutor(index, int(a), int(b), q, chosen, reference, frames)
