"""Template tags of the patient's progress charts and pain chart: the pages include a template
that asks for its data here, so the views stay as they are."""

from __future__ import annotations

from django import template

from webapp.patients.pain import pain_chart
from webapp.patients.progress import progress_charts

register = template.Library()


@register.simple_tag
def progress_charts_of(patient) -> list:
    """Per exercise, the series its progress charts draw (`progress_charts`)."""
    return progress_charts(patient)


@register.simple_tag
def pain_chart_of(patient) -> dict:
    """The pain score of each session with one, laid out as a chart (`pain_chart`)."""
    return pain_chart(patient)
