"""The recording page's part for a recording without exercise: the recognition's progress, its
suggestion to confirm or the choice of another exercise (`webapp.recordings.recognition`)."""

from __future__ import annotations

from django import template

from webapp.recordings.recognition import UNDER_WAY, confirm_form, suggestion_offered

register = template.Library()


@register.inclusion_tag("recordings/_recognition.html", takes_context=True)
def recognition_box(context, recording):
    form = confirm_form(context["request"].user, recording)
    return {
        "recording": recording,
        "form": form,
        "suggested": suggestion_offered(form),
        "under_way": recording.recognition in UNDER_WAY,
    }
