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

from analysis.assessment.findings import Reference, RepetitionMeasures, plainly_off
from analysis.assessment.scoring import MISSED_CAP
from analysis.pipeline.model import FittedModel
from analysis.pipeline.results import RepetitionResult
from analysis.pipeline.tutor_parts import stretches

FloatArray = npt.NDArray[np.float64]


def tutor_reference(model: FittedModel) -> Reference:
    """The tutor's median range, its SD and median posture per clinical angle (and per
    compensation) over the tutor's repetitions, and the angles the exercise trains (computed
    when the model was built: `analysis.pipeline.tutor_parts.reference_of`)."""
    return model.tutor_parts.reference


def repetition_measures(
    repetitions: Sequence[RepetitionResult], series: Mapping[str, FloatArray] | None = None
) -> list[RepetitionMeasures]:
    """Each repetition's angle ranges, postures (middles of the ranges), tempo and pass (a
    verdict not stored counts as not passed); with the recording's compensation ``series``
    (`tutor_parts.compensations`), their ranges and middles too."""
    extra = stretches(series or {}, [(r.start, r.end) for r in repetitions])
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
    repetitions: Sequence[RepetitionResult],
    model: FittedModel,
    mirrored: bool,
    series: Mapping[str, FloatArray],
) -> tuple[RepetitionResult, ...]:
    """The repetitions, those with a plain error (`analysis.assessment.findings.plainly_off`:
    a main angle far short of the tutor's range, the trunk held far off its posture) scored at
    most `MISSED_CAP`, so failed: a pass never sits beside a large correction; ``series``: the
    recording's compensations (`tutor_parts.compensations`)."""
    reference = tutor_reference(model)
    measures = repetition_measures(repetitions, series)
    return tuple(
        replace(r, score=min(r.score, MISSED_CAP), passed=False)
        if plainly_off(m, reference, mirrored) else r
        for r, m in zip(repetitions, measures, strict=True)
    )  # fmt: skip
