"""Template tags of the clinical measures (recording page, progress page): the pages include a
template that asks for its data here, so the views stay as they are."""

from __future__ import annotations

from django import template

from webapp.recordings.clinical import clinical_context
from webapp.recordings.sources import SourceReliability, source_reliability

register = template.Library()


@register.simple_tag
def clinical_measures(result, exercise=None) -> dict:
    """`webapp.recordings.clinical.clinical_context` of a run's result."""
    return clinical_context(result, exercise)


@register.simple_tag
def clinical_progress_of(patient) -> list:
    """Per exercise, each clinical angle's range and each hand's reachable area over dates."""
    from webapp.patients.progress import clinical_progress

    return clinical_progress(patient)


@register.filter
def reliability(result) -> SourceReliability:
    """How far the angles of this recording's capture source can be trusted, in words."""
    return source_reliability(result.source)


@register.filter
def degrees(value, digits: int = 0) -> str:
    """A figure in degrees ("95°"); a dash when there is none."""
    if value is None or value == "":
        return "–"
    return f"{float(value):.{int(digits)}f}°"
