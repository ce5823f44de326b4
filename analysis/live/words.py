"""What a live session says to the patient when a repetition ends: the first of the reasons its
judgement gives (`analysis.pipeline.judgement`, the same judgement as the offline analysis of the
same frames), or "well done" for a repetition that passed without one."""

from __future__ import annotations

from typing import Any

Event = dict[str, Any]


def repetition_words(event: Event, threshold: float | None = None) -> str:
    """What the patient reads (and hears) when a repetition ends: its first reason (a failed
    repetition always has one; a passed one may have a tip), else "well done" for a passed one.
    ``threshold``: kept for callers of the old signature (a score is not a reason)."""
    number = event["index"] + 1
    reasons = list(event.get("reasons") or ())
    reasons += [g["text"] for g in event.get("guidance", ()) if g.get("text")]
    if reasons:
        return f"Repetition {number}: {reasons[0]}"
    if event["passed"]:
        return f"Repetition {number}: well done."
    return f"Repetition {number}: not done as the demonstration: watch it and follow its movement."
