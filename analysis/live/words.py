"""What a live session says to the patient: each piece of guidance in plain words, and the
sentence read (and spoken) when a repetition ends."""

from __future__ import annotations

from typing import Any

Event = dict[str, Any]
GUIDANCE_TEXT = {
    "too fast": "Slow down: take as long as the tutor.",
    "too slow": "A little faster: keep the tutor's pace.",
    "overdone": "Not so far: stop where the tutor stops.",
    "incomplete": "Go further: reach the tutor's end position.",
}


def repetition_words(event: Event, threshold: float) -> str:
    """What the patient reads (and hears) when a repetition ends: "well done" only for one that
    passed without a tip; a tip when there is one; a failed repetition without a tip is told its
    score against the pass mark, so it always hears why it was not praised."""
    number = event["index"] + 1
    tips = [g["text"] for g in event["guidance"] if g.get("text")]
    if tips:
        return f"Repetition {number}: {tips[0]}"
    if event["passed"]:
        return f"Repetition {number}: well done."
    return (
        f"Repetition {number}: not counted as done well: score {event['score']:.0f}, "
        f"{threshold:.0f} passes."
    )
