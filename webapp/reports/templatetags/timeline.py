"""Template tags of the recording page's timeline (see `webapp.reports.timeline`)."""

from __future__ import annotations

from typing import Any

from django import template

from webapp.recordings.reading import reading_of
from webapp.reports import timeline as build

register = template.Library()

# What the worker reports besides the pipeline's own stage labels (run_status.js keeps the same).
STAGE_WORDS = {"loading": "loading the recording", "done": "saving the result"}


@register.simple_tag
def recording_timeline(run, recording) -> dict[str, Any] | None:
    """The timeline of a succeeded run, None otherwise."""
    if run is None or run.status != "succeeded" or not run.summary:
        return None
    names = recording.exercise.landmark_type_names if recording.exercise else {}
    return build.timeline(
        run.result, {str(k): str(v) for k, v in (names or {}).items()}, run.summary,
        fallback_frames=recording.n_frames or 0, reading=reading_of(run),
    )  # fmt: skip


@register.filter
def stage_words(stage: str) -> str:
    return STAGE_WORDS.get(stage, stage)
