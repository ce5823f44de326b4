"""What every analysis reads of the exercise's reference (the tutor) and which depends on the
model alone, computed once when the model is built (`fit_tutor_parts`) and stored with it: the
tutor's clinical reference (each angle's median range, its spread and posture over the tutor's
repetitions, the angles the exercise trains: `analysis.assessment.findings.Reference`), the
tutor's take for the playback (local rotations and translations, key poses), its per-joint
movement amplitudes and retrieval features (`analysis.pipeline.match`) and its body parts.

The measuring helpers a recording shares with its tutor live here too: the compensations
(`compensations`) and their ranges over stretches of frames (`stretches`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.adjustment import Performance
from analysis.assessment.compensations import compensation_series, stretch, trained
from analysis.assessment.findings import Reference, involved_angles, tutor_ranges, tutor_spreads
from analysis.bvh import Motion, Skeleton
from analysis.clinical import angle_ranges, measure
from analysis.clinical.body import Body, find_body, find_joints, take_vertical
from analysis.kinematics import Kinematics, kinematics, scaled_positions
from analysis.landmarks import KeyPoses
from analysis.pipeline.gestures import reference_excursion
from analysis.pipeline.model_fit import ModelComponents
from analysis.retrieval import recording_features

FloatArray = npt.NDArray[np.float64]
Stretch = tuple[dict[str, float], dict[str, float]]  # per angle: range, middle
RETRIEVAL_FPS = 15.0

# a body role (analysis.clinical.body) -> the joint whose clinical angles its rotation moves
ANGLE_JOINT = {
    "collar": "shoulder", "shoulder": "shoulder", "elbow": "elbow", "wrist": "elbow",
    "hip": "hip", "knee": "knee", "ankle": "ankle", "toe": "ankle",
    "pelvis": "trunk", "spine": "trunk", "chest": "trunk", "neck": "trunk",
}  # fmt: skip


@dataclass(frozen=True, eq=False)
class PaceReference:
    """What paper 001's pace and reach rules compare a repetition with: the involved joints
    (``index``), their mirror images' joints, the tutor's excursion of both
    (`gestures.reference_excursion`) and the tutor's repetition length (median, model frames)."""

    index: list[int]
    mirror: list[int]
    excursion: FloatArray
    tutor_frames: float


@dataclass(frozen=True, eq=False)
class TutorParts:
    """The model-only inputs of every analysis (module docstring): ``reference`` (clinical
    angles and compensations), ``take`` (the tutor's rotations, translations and key poses for
    the playback), ``amplitudes`` (J,) per-joint movement, ``features`` (F, 17) retrieval
    features at `RETRIEVAL_FPS`, ``pace`` the pace rules' reference, ``body`` the tutor's body
    parts."""

    reference: Reference
    take: Performance
    amplitudes: FloatArray
    features: FloatArray
    pace: PaceReference
    body: Body


def amplitudes(points: FloatArray) -> FloatArray:
    """(J,) how much each joint moves: the root of its summed positional variance."""
    return np.asarray(np.sqrt(points.var(axis=0).sum(axis=-1)), dtype=np.float64)


def features_of(motion: Motion, kin: Kinematics | None = None) -> FloatArray:
    """A take's retrieval features ((F, 17) at 15 fps), as `match.Candidate.features` holds
    them; ``kin``: its kinematics when already computed."""
    world = (kin or kinematics(motion)).positions
    return recording_features(world, motion.skeleton.names, motion.fps, target_fps=RETRIEVAL_FPS)


def ticked_joints(skeleton: Skeleton, involved_joints: Sequence[str]) -> set[str]:
    """The exercise's involved joints as the joints of clinical angles ("knee_left", "trunk")."""
    role_of = {skeleton.names[i]: role for role, i in find_joints(skeleton).items()}
    out = set()
    for name in involved_joints:
        base, _, side = role_of.get(name, "").partition("_")
        joint = ANGLE_JOINT.get(base)
        if joint:
            out.add(joint if joint == "trunk" or not side else f"{joint}_{side}")
    return out


def compensations(positions: FloatArray, body: Body) -> dict[str, FloatArray]:
    """The compensations the rig's joints allow (`analysis.assessment.compensations`), from a
    take's world positions (F, J, 3) and its body parts."""
    up = body.up if body.upright else take_vertical(positions, body)
    return compensation_series(positions, body.joints, up)


def stretches(series: Mapping[str, FloatArray], bounds: Sequence[tuple[int, int]]) -> list[Stretch]:
    """Per (start, end): each compensation's range and middle over those frames (degrees)."""
    out = []
    for start, end in bounds:
        part = stretch(series, start, end)
        out.append(({k: float(np.ptp(v)) for k, v in part.items()},
                    {k: float(v.min() + v.max()) / 2 for k, v in part.items()}))  # fmt: skip
    return out


def reference_of(
    tutor: Motion,
    bounds: Sequence[tuple[int, int]],
    involved_joints: Sequence[str],
    seen: tuple[Kinematics, Body],
) -> Reference:
    """The tutor's median range, its SD and median posture per clinical angle (and per
    compensation) over its repetitions ``bounds``, and the angles the exercise trains;
    ``seen``: the tutor's kinematics and body parts."""
    kin, body = seen
    series = measure(tutor, kin=kin, body=body).series
    per_repetition = [angle_ranges(series, a, b) for a, b in bounds]
    ranges = [{k: v.range for k, v in rep.items()} for rep in per_repetition]
    middles = [{k: (v.min + v.max) / 2 for k, v in rep.items()} for rep in per_repetition]
    ticked, spread = ticked_joints(tutor.skeleton, involved_joints), tutor_spreads(ranges)
    involved = involved_angles(tutor_ranges(ranges), ticked, spread)
    moved = involved_angles(tutor_ranges(ranges), ticked)  # a plain error's main angles
    measured = stretches(compensations(kin.positions, body), bounds)
    # what the exercise itself moves (a trunk rotation's turn) is never checked as a compensation
    own = trained(tutor_ranges([extent for extent, _ in measured]))
    for k, (extent, middle) in enumerate(measured):
        ranges[k] = {**ranges[k], **{n: v for n, v in extent.items() if n not in own}}
        middles[k] = {**middles[k], **{n: v for n, v in middle.items() if n not in own}}
    return Reference(
        tutor_ranges(ranges), tutor_spreads(ranges), tutor_ranges(middles), involved, moved
    )  # fmt: skip


def pace_reference_of(parts: ModelComponents, local_q: FloatArray) -> PaceReference:
    """The `PaceReference` of a model's fitted parts and its tutor's local rotations."""
    papers = parts.papers
    index = list(papers.joint_index)
    mirror = [parts.mirror[j] for j in index]
    reps, step = parts.tutor_reps, parts.scoring_step
    excursion = reference_excursion(papers.tutor_q, local_q[:, mirror], reps, step)
    tutor_frames = float(np.median([b - a + 1 for a, b in reps])) if reps else 1.0
    return PaceReference(index, mirror, excursion, tutor_frames)


def fit_tutor_parts(
    tutor: Motion,
    key_poses: KeyPoses,
    parts: ModelComponents,
    involved_joints: Sequence[str],
) -> TutorParts:
    """Everything of `TutorParts` from one forward-kinematics pass of the tutor; ``landmarks``:
    its key poses; ``parts``: the model's fitted parts (its repetitions, the
    pace rules' joints)."""
    kin, body = kinematics(tutor), find_body(tutor.skeleton)
    bounds = parts.tutor_reps
    take = Performance(kin.local_q, kin.local_t, key_poses)
    every = list(range(len(tutor.skeleton.names)))
    return TutorParts(
        reference=reference_of(tutor, bounds, involved_joints, (kin, body)),
        take=take,
        amplitudes=amplitudes(scaled_positions(tutor, every, kin)),
        features=_features_or_none(tutor, kin),
        pace=pace_reference_of(parts, kin.local_q),
        body=body,
    )


def _features_or_none(tutor: Motion, kin: Kinematics) -> FloatArray:
    """The tutor's retrieval features; an empty (0, 0) array when its body parts cannot be found
    (then `match.rank` compares with no other exercise, as before)."""
    try:
        return features_of(tutor, kin)
    except ValueError:
        return np.zeros((0, 0))
