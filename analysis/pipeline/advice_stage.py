"""What the feedback stage (`analysis.pipeline.stages.feedback_items`) compares: the tutor's
reference in clinical angles (each angle's median range and posture over its repetitions, the
spread of the range, the angles the exercise trains) and the patient's repetitions measured the
same way, with the compensations measured from positions (`analysis.assessment.findings`,
`analysis.assessment.compensations`); and the check that fails a repetition whose error is plain
whatever its score (`plain_errors_fail`, run after the clinical angles, before the feedback)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np
import numpy.typing as npt

from analysis.assessment.compensations import compensation_series, stretch
from analysis.assessment.findings import (
    Reference,
    RepetitionMeasures,
    involved_angles,
    plainly_off,
    tutor_ranges,
    tutor_spreads,
)
from analysis.assessment.scoring import MISSED_CAP
from analysis.bvh import Motion
from analysis.clinical import angle_ranges, angle_series
from analysis.clinical.body import find_body, find_joints, take_vertical
from analysis.kinematics import positions
from analysis.pipeline.model import FittedModel
from analysis.pipeline.results import RepetitionResult

FloatArray = npt.NDArray[np.float64]
Stretch = tuple[dict[str, float], dict[str, float]]  # per angle: range, middle

# a body role (analysis.clinical.body) -> the joint whose clinical angles its rotation moves
ANGLE_JOINT = {
    "collar": "shoulder", "shoulder": "shoulder", "elbow": "elbow", "wrist": "elbow",
    "hip": "hip", "knee": "knee", "ankle": "ankle", "toe": "ankle",
    "pelvis": "trunk", "spine": "trunk", "chest": "trunk", "neck": "trunk",
}  # fmt: skip


def ticked_joints(model: FittedModel) -> set[str]:
    """The exercise's involved joints as the joints of clinical angles ("knee_left", "trunk")."""
    skeleton = model.tutor.skeleton
    role_of = {skeleton.names[i]: role for role, i in find_joints(skeleton).items()}
    out = set()
    for name in model.involved_joints:
        base, _, side = role_of.get(name, "").partition("_")
        joint = ANGLE_JOINT.get(base)
        if joint:
            out.add(joint if joint == "trunk" or not side else f"{joint}_{side}")
    return out


def compensations(motion: Motion) -> dict[str, FloatArray]:
    """The compensations the rig's joints allow (`analysis.assessment.compensations`)."""
    body = find_body(motion.skeleton)
    pos = positions(motion)
    up = body.up if body.upright else take_vertical(pos, body)
    return compensation_series(pos, body.joints, up)


def _stretches(
    series: Mapping[str, FloatArray], bounds: Sequence[tuple[int, int]]
) -> list[Stretch]:
    """Per (start, end): each compensation's range and middle over those frames (degrees)."""
    out = []
    for start, end in bounds:
        part = stretch(series, start, end)
        out.append(({k: float(np.ptp(v)) for k, v in part.items()},
                    {k: float(v.min() + v.max()) / 2 for k, v in part.items()}))  # fmt: skip
    return out


def tutor_reference(model: FittedModel) -> Reference:
    """The tutor's median range, its SD and median posture per clinical angle (and per
    compensation) over the tutor's repetitions, and the angles the exercise trains."""
    series = angle_series(model.tutor)
    bounds = list(model.components.tutor_reps)
    per_repetition = [angle_ranges(series, a, b) for a, b in bounds]
    ranges = [{k: v.range for k, v in rep.items()} for rep in per_repetition]
    middles = [{k: (v.min + v.max) / 2 for k, v in rep.items()} for rep in per_repetition]
    ticked, spread = ticked_joints(model), tutor_spreads(ranges)
    involved = involved_angles(tutor_ranges(ranges), ticked, spread)
    moved = involved_angles(tutor_ranges(ranges), ticked)  # a plain error's main angles
    for k, (extent, middle) in enumerate(_stretches(compensations(model.tutor), bounds)):
        ranges[k] = {**ranges[k], **extent}
        middles[k] = {**middles[k], **middle}
    return Reference(
        tutor_ranges(ranges), tutor_spreads(ranges), tutor_ranges(middles), involved, moved
    )  # fmt: skip


def repetition_measures(
    repetitions: Sequence[RepetitionResult], motion: Motion | None = None
) -> list[RepetitionMeasures]:
    """Each repetition's angle ranges, postures (middles of the ranges), tempo and pass (a
    verdict not stored counts as not passed); with the recording's ``motion``, its
    compensations' too."""
    series = compensations(motion) if motion is not None else {}
    extra = _stretches(series, [(r.start, r.end) for r in repetitions])
    return [
        RepetitionMeasures(
            r.start, {**{k: v.range for k, v in r.clinical_angles.items()}, **ranges}, r.tempo,
            r.passed is True,
            {**{k: (v.min + v.max) / 2 for k, v in r.clinical_angles.items()}, **middles},
            r.reach, tuple(g.type for g in r.guidance),
        )
        for r, (ranges, middles) in zip(repetitions, extra, strict=True)
    ]  # fmt: skip


def recording_passed(repetitions: Sequence[RepetitionResult], model: FittedModel) -> bool:
    """Whether the recording's score (the mean repetition score) reaches the pass threshold."""
    scores = [r.score for r in repetitions]
    return bool(scores) and float(np.mean(scores)) >= model.components.papers.threshold.value


def plain_errors_fail(
    repetitions: Sequence[RepetitionResult], model: FittedModel, mirrored: bool, motion: Motion
) -> tuple[RepetitionResult, ...]:
    """The repetitions, those with a plain error (`analysis.assessment.findings.plainly_off`:
    a main angle far short of the tutor's range, the trunk held far off its posture) scored at
    most `MISSED_CAP`, so failed: a pass never sits beside a large correction."""
    reference = tutor_reference(model)
    measures = repetition_measures(repetitions, motion)
    return tuple(
        replace(r, score=min(r.score, MISSED_CAP), passed=False)
        if plainly_off(m, reference, mirrored) else r
        for r, m in zip(repetitions, measures, strict=True)
    )  # fmt: skip
