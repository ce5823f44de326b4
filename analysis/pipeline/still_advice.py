"""Corrections for a recording in which the exercise's own body parts hardly moved (issue 26).

When the arm a shoulder abduction trains stays down all through, no repetition is found and the
recording "does not look like the exercise" (`analysis.pipeline.match`): no score, and until now
no correction either, so the patient was not told what was missing. Here the angles the exercise
trains (`analysis.assessment.findings.involved_angles`, on the tutor's side: with no repetition
there is no telling which side the patient meant) are measured over the whole recording — each
angle's excursion, its 5–95th percentile span, so a stray frame does not count — and compared
with the tutor's median range as one failed repetition. Only the parts that covered less than
`STILL_SHARE` of the tutor's range are corrected ("Raise your right arm higher, by about 86°: it
rose 2° against the demonstration's 88° (2 % of its range) in the whole recording."); a
recording that moved them but matched another exercise gets none (it says which exercise it
looks like instead).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from analysis.assessment.findings import PLAIN_SHARE, Finding, RepetitionMeasures, findings
from analysis.assessment.limbs import arm_first
from analysis.feedback import Grammar
from analysis.feedback.advice import MAX_CORRECTIONS, Advice, Correction, direction_of, fields, say
from analysis.feedback.text import correction_rules
from analysis.pipeline.advice_stage import main_part, tutor_reference
from analysis.pipeline.model import FittedModel

FloatArray = npt.NDArray[np.float64]
STILL_SHARE = PLAIN_SHARE  # an involved angle covering less of the tutor's range: left out
WHOLE = "the whole recording"  # what the sentences' {repetitions} say: there was none


def excursions(series: Mapping[str, FloatArray]) -> dict[str, float]:
    """Each angle's excursion over the recording: its 5–95th percentile span (degrees)."""
    out = {}
    for name, values in series.items():
        finite = values[np.isfinite(values)]
        if finite.size:
            low, high = np.percentile(finite, [5, 95])
            out[name] = float(high - low)
    return out


def still_findings(series: Mapping[str, FloatArray], model: FittedModel) -> list[Finding]:
    """The involved angles that hardly moved over the whole recording (module docstring)."""
    reference = tutor_reference(model)
    whole = RepetitionMeasures(0, excursions(series), 1.0, passed=False)
    found = arm_first(findings([whole], reference))
    return [f for f in found if f.kind == "less" and f.patient < STILL_SHARE * f.tutor]


def still_advice(series: Mapping[str, FloatArray], model: FittedModel) -> Advice:
    """The corrections of `still_findings`, said by the exercise's grammar (the default
    sentences where it has no rule), the whole recording in place of the repetitions."""
    speakers = (model.rules, Grammar(tuple(correction_rules())))
    part = main_part(tutor_reference(model).ranges)
    corrections = []
    for finding in still_findings(series, model)[:MAX_CORRECTIONS]:
        values = {**fields(finding, 1, part), "repetitions": WHOLE}
        text = next((t for g in speakers if (t := say(g, finding, values))), None)
        if text is not None:
            corrections.append(Correction(
                text, values["part"], direction_of(finding), finding.amount, "°", (), 0,
                finding.angle,
            ))  # fmt: skip
    return Advice(tuple(corrections))
