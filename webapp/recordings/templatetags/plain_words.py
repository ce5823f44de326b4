"""Template filters of the one vocabulary for people (`webapp.recordings.words`):
``{{ level.joint|body_part }}``, ``{{ n|plural:"repetition" }}``, ``{% level_help %}``,
``{{ seconds|duration }}``."""

from __future__ import annotations

import re

from django import template

from webapp.recordings import words

register = template.Library()


@register.filter
def body_part(joint) -> str:
    """A rig joint name in anatomical words ("LeftUpperArm" → "left upper arm")."""
    return words.body_part(str(joint))


@register.filter
def plural(count, word: str) -> str:
    """``{{ 1|plural:"repetition" }}`` → "1 repetition"; "word,words" for irregular plurals."""
    one, _, many = str(word).partition(",")
    try:
        number = int(count)
    except (TypeError, ValueError):
        number = 0
    return words.plural(number, one, many or None)


@register.simple_tag
def level_help() -> str:
    return words.LEVEL_HELP


@register.filter
def duration(seconds) -> str:
    """Seconds as people say them: "37.8 s", "1 min 12 s"."""
    try:
        value = float(seconds)
    except (TypeError, ValueError):
        return "–"
    if value < 60:
        return f"{value:.1f} s"
    minutes, rest = divmod(round(value), 60)
    return f"{minutes} min {rest} s"


@register.filter
def key_pose(kind, names) -> str:
    """``{{ type|key_pose:exercise.landmark_type_names }}``: "end of range", or "second marked
    position of the movement" for a kind named only by its number."""
    return words.key_pose_name(kind, names if isinstance(names, dict) else {})


UUID = re.compile(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}", re.IGNORECASE)


@register.filter
def without_ids(text) -> str:
    """A path or text with its record ids shortened to "…" ("/patients/…/"): ids mean nothing
    to a reader (the full text stays available, e.g. in a link's title)."""
    return UUID.sub("…", str(text))
