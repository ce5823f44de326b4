"""What the feedback stage (`analysis.pipeline.stages.feedback_items`) compares: the tutor's
reference in clinical angles (each angle's median range and posture over its repetitions, the
spread of the range, the angles the exercise trains) and the patient's repetitions measured the
same way, with the compensations measured from positions (`analysis.assessment.findings`,
`analysis.assessment.compensations`); and each repetition's judgement (`judge_repetitions`, run
after the clinical angles, before the feedback: `analysis.pipeline.judgement`), which fails a
repetition whose error is plain whatever its score."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np
import numpy.typing as npt

from analysis.assessment.findings import Finding, Reference, RepetitionMeasures, swapped_side
from analysis.assessment.scoring import MISSED_CAP
from analysis.clinical.labels import angle_part
from analysis.feedback import Grammar
from analysis.feedback.text import correction_rules
from analysis.pipeline.gestures import Pace, usual_for_patient
from analysis.pipeline.judgement import Judge, Judgement, RepetitionFacts, judge
from analysis.pipeline.model import FittedModel
from analysis.pipeline.repetition_stage import RULES
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


def main_part(tutor: Mapping[str, float]) -> str:
    """What the tutor moves most, in plain words ("both arms", "left knee", "trunk")."""
    if not tutor:
        return "body"
    top = max(tutor, key=lambda k: tutor[k])
    other = tutor.get(swapped_side(top), 0.0)
    if other != tutor[top] and other >= 0.7 * tutor[top]:
        return angle_part(top).split(" ", 1)[1] + "s"  # "elbows": both sides move
    return angle_part(top)


def judge_of(model: FittedModel, mirrored: bool) -> Judge:
    """What a recording's repetitions are judged against (`analysis.pipeline.judgement`):
    the exercise's grammar, then the default sentences where it has no rule."""
    reference = tutor_reference(model)
    speakers = (model.rules, Grammar(tuple(correction_rules())))
    threshold = float(model.components.papers.threshold.value)
    return Judge(reference, mirrored, threshold, speakers, main_part(reference.ranges))


def facts_of(
    rep: RepetitionResult, measures: RepetitionMeasures, number: int, own: Pace | None
) -> RepetitionFacts:
    """A repetition's measurements for `judge`: the tempo and reach paper 001's rule judged."""
    kinds = tuple(g.type for g in rep.guidance)
    usual = tuple(k for k in kinds if usual_for_patient(k, own, RULES))
    return RepetitionFacts(number, rep.score, kinds, measures, usual)


def judge_repetitions(
    repetitions: Sequence[RepetitionResult],
    model: FittedModel,
    mirrored: bool,
    series: Mapping[str, FloatArray],
    own: Pace | None = None,
) -> tuple[tuple[RepetitionResult, ...], tuple[Judgement, ...]]:
    """Every repetition judged once (`analysis.pipeline.judgement.judge`): its verdict (a plain
    error fails it whatever its score, so a pass never sits beside a large correction), its
    guidance (one type per axis, none against its corrections) and its reasons; ``series``:
    the recording's compensations (`tutor_parts.compensations`); ``own``: the patient's usual
    pace from an earlier session (softer words for what is usual for this patient)."""
    judge_ = judge_of(model, mirrored)
    measures = repetition_measures(repetitions, series)
    out, judged = [], []
    for k, (rep, m) in enumerate(zip(repetitions, measures, strict=True)):
        verdict = judge(facts_of(rep, m, k + 1, own), judge_)
        kept = tuple(g for g in rep.guidance if g.type in verdict.guidance)
        # a plain error caps the score, so a failed repetition never scores a pass
        plain = not verdict.passed and rep.score >= judge_.threshold
        score = min(rep.score, MISSED_CAP) if plain else rep.score
        out.append(replace(rep, score=score, passed=verdict.passed, guidance=kept,
                           reasons=verdict.reasons))  # fmt: skip
        judged.append(verdict)
    return tuple(out), tuple(judged)


def unnamed_failures(
    found: Sequence[Finding], judged: Sequence[Judgement], starts: Sequence[int]
) -> list[Finding]:
    """The findings with every failed repetition no correction names added to a correction of
    its own first difference (`Judgement.hits`; grouped by kind and angle): so a recording with
    a failed repetition always has something to correct. What went well for a body part a
    correction names is left out (never praised and corrected at once; tempo is no part)."""
    named = {n for f in found if f.kind != "good" for n in f.repetitions}
    groups: dict[tuple[str, str], list[tuple[int, Finding]]] = {}
    for k, verdict in enumerate(judged):
        if not verdict.passed and k + 1 not in named and verdict.hits:
            hit = verdict.hits[0]
            groups.setdefault((hit.kind, hit.angle), []).append((k + 1, hit))
    added = [
        Finding(kind, angle, float(np.median([h.amount for _, h in hits])), hits[0][1].tutor,
                float(np.median([h.patient for _, h in hits])), tuple(n for n, _ in hits),
                starts[hits[0][0] - 1], len(hits) / max(len(judged), 1))
        for (kind, angle), hits in groups.items()
    ]  # fmt: skip
    corrected = {angle_part(f.angle) for f in [*found, *added] if f.kind != "good" and f.angle}
    kept = [f for f in found if f.kind != "good" or angle_part(f.angle) not in corrected]
    cut = next((i for i, f in enumerate(kept) if f.kind == "good"), len(kept))
    return [*kept[:cut], *added, *kept[cut:]]
