"""Whether the recording page shows the uploaded video beside the skeletons."""

from __future__ import annotations

from django import template
from django.urls import reverse

from webapp.recordings.models import Recording
from webapp.recordings.video_views import video_suffix

register = template.Library()


@register.simple_tag
def recording_video_url(recording: Recording) -> str:
    """The address of the recording's video (`video_views.video`), or "" when it is not one."""
    if video_suffix(recording) is None:
        return ""
    return reverse("recordings:video", args=[recording.pk])
