"""``{% live_exercises prescriptions as choices %}``: what the patient page's "Start a live
session" offers, chosen here from the prescriptions the page has already read (no query), so the
patient page's own view need not know about live sessions."""

from __future__ import annotations

from collections.abc import Iterable

from django import template

from webapp.exercises.models import Exercise
from webapp.live import services
from webapp.patients.models import Prescription

register = template.Library()


@register.simple_tag
def live_exercises(prescriptions: Iterable[Prescription]) -> list[Exercise]:
    return services.startable_of(prescriptions)


@register.simple_tag
def live_camera_prescriptions(prescriptions: Iterable[Prescription]) -> list[Prescription]:
    """The prescriptions whose exercise the camera page can follow (one per exercise)."""
    startable = {exercise.pk for exercise in services.startable_of(prescriptions)}
    chosen: dict[object, Prescription] = {}
    for prescription in prescriptions:
        if prescription.exercise_id in startable:
            chosen.setdefault(prescription.exercise_id, prescription)
    return sorted(chosen.values(), key=lambda p: p.exercise.name)
