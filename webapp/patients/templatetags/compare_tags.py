"""Template tags of the compare page's links: the recording page includes a small template that
asks here for the patient's first session, so the recording view stays as it is."""

from __future__ import annotations

from django import template
from django.urls import reverse
from django.utils.http import urlencode

from webapp.patients.compare import first_of_exercise

register = template.Library()


@register.simple_tag
def compare_with_first_url(recording) -> str:
    """The compare page of the patient's first analysed session of this exercise (a) and this
    recording (b); "" when this recording is that first session or has no exercise."""
    first = first_of_exercise(recording)
    if first is None or first.pk == recording.pk:
        return ""
    page = reverse("patients:compare", kwargs={"pk": recording.patient_id})
    return f"{page}?{urlencode({'a': first.pk, 'b': recording.pk})}"
