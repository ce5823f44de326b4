"""The exercise model: everything the pipeline needs about one exercise, fitted once from its tutor.

`build_model` takes the tutor recording with its key poses (landmark frames and types) and,
optionally, therapist-labelled training recordings. It fits the movement features (which joints
move, the progress axis used to find repetitions, the tutor's repetition templates), the score
scale, the tutor's mean pose per landmark type, the assessment thresholds and the default
feedback grammar. `dump_model` / `load_model` store it as one versioned file; loading refuses a
file written by an incompatible format.
"""

from __future__ import annotations

import io
import pickle
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import IO, Any

import numpy as np
import numpy.typing as npt

from analysis import __version__ as code_version
from analysis.bvh import Motion
from analysis.dtw.cost_blas import single_threaded_blas
from analysis.feedback import Grammar, default_grammar
from analysis.landmarks import KeyPoses
from analysis.pipeline.model_fit import (
    ModelComponents,
    TrainingRecording,
    TutorKeyPosesError,
    fit_components,
)
from analysis.pipeline.tutor_parts import TutorParts, fit_tutor_parts

# 3: one calibrated score scale (pass at 70), corrections; 4: tutor-distance scale;
# 5: the parsed grammar and the tutor's parts (`tutor_parts`) stored with the model;
# 6: key poses in one form; 7: the reference leaves out what the exercise trains (a trunk
# rotation's turn is never checked as a compensation), and the judgement's inputs
FORMAT_VERSION = 7
MAGIC = b"PHYSIO-MODEL\n"
FloatArray = npt.NDArray[np.float64]
Progress = Callable[[str, float], None]


class ModelVersionError(ValueError):
    """A saved exercise model was written by an incompatible version of this code."""


@dataclass(frozen=True, eq=False)
class FittedModel:
    """A fitted exercise model (see the module docstring); ``components`` holds fitted parts,
    ``rules`` the parsed ``grammar`` and ``tutor_parts`` what every analysis reads of the tutor
    (both depend on the model alone, so they are computed once, when it is built)."""

    format_version: int
    code_version: str
    tutor: Motion
    key_poses: KeyPoses  # the tutor's, as marked by the therapist
    type_names: dict[int, str]
    involved_joints: tuple[str, ...]
    grammar: str
    components: ModelComponents
    rules: Grammar
    tutor_parts: TutorParts
    report: dict[str, Any] = field(default_factory=dict)

    @property
    def joint_names(self) -> tuple[str, ...]:
        return self.tutor.skeleton.names

    @property
    def fps(self) -> float:
        return self.tutor.fps


def _check_landmarks(tutor: Motion, frames: Sequence[int], types: Sequence[int]) -> None:
    if len(frames) != len(types) or len(frames) < 2:
        raise TutorKeyPosesError(
            f"its reference has {len(frames)} key poses with {len(types)} types; it needs as "
            "many types as key poses, and at least two"
        )
    if any(f < 0 or f >= tutor.n_frames for f in frames):
        raise TutorKeyPosesError(
            f"its key poses must lie within the reference's {tutor.n_frames} frames"
        )
    if list(frames) != sorted(frames):
        raise TutorKeyPosesError("its key poses must be in time order")
    if 1 not in types:
        raise TutorKeyPosesError("none of its key poses marks where a repetition starts")


def build_model(
    tutor: Motion,
    landmark_frames: Sequence[int],
    landmark_types: Sequence[int],
    *,
    joints: Sequence[str] | None = None,
    type_names: Mapping[int, str] | None = None,
    grammar: str | None = None,
    training: Sequence[TrainingRecording] = (),
    on_progress: Progress | None = None,
) -> FittedModel:
    """Fit the model of an exercise from its tutor (and labelled recordings, if any)."""
    _check_landmarks(tutor, landmark_frames, landmark_types)
    names = dict(type_names or {})
    for t in sorted(set(landmark_types)):
        names.setdefault(int(t), "start" if t == 1 else f"key pose {t}")
    with single_threaded_blas():  # as in `analyse`: each of the fit's DTW cost blocks only counts
        components, involved, report = fit_components(
            tutor, list(landmark_frames), list(landmark_types), joints, training, on_progress
        )
    text = grammar or default_grammar(list(involved), names)
    rules = Grammar.parse(text)  # a bad grammar fails the build, not every analysis
    key_poses = KeyPoses.of(landmark_frames, landmark_types)
    tutor_parts = fit_tutor_parts(tutor, key_poses, components, involved)
    return FittedModel(
        format_version=FORMAT_VERSION,
        code_version=code_version,
        tutor=tutor,
        key_poses=key_poses,
        type_names=names,
        involved_joints=tuple(involved),
        grammar=text,
        components=components,
        rules=rules,
        tutor_parts=tutor_parts,
        report=report,
    )


def dump_model(model: FittedModel, out: IO[bytes]) -> None:
    """Write the model (a format header, then a pickle of the fitted parts)."""
    out.write(MAGIC)
    out.write(f"{FORMAT_VERSION}\n".encode())
    pickle.dump(model, out, protocol=pickle.HIGHEST_PROTOCOL)


def load_model(source: bytes | IO[bytes]) -> FittedModel:
    """Read a model written by `dump_model`; refuses other formats. Only load files you wrote."""
    stream = io.BytesIO(source) if isinstance(source, bytes) else source
    if stream.read(len(MAGIC)) != MAGIC:
        raise ModelVersionError("this is not an exercise model file")
    version = stream.readline().strip()
    if version != str(FORMAT_VERSION).encode():
        raise ModelVersionError(
            f"the model was saved in format {version.decode(errors='replace')}; this code reads "
            f"format {FORMAT_VERSION}. Rebuild the exercise model."
        )
    model = pickle.load(stream)
    if not isinstance(model, FittedModel):
        raise ModelVersionError("the model file holds something else")
    return model
