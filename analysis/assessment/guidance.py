"""Guidance for one repetition (paper 001, Table 1): too fast, too slow, overdone, incomplete.

Tempo is the repetition's duration over the tutor's; reach is how far along the tutor's movement
axis the repetition went (1 = the tutor's end of range). Thresholds are deliberately wide: a tip
is worth giving only when the difference is plain to see.
"""

from __future__ import annotations

TOO_FAST, TOO_SLOW, OVERDONE, INCOMPLETE = "too fast", "too slow", "overdone", "incomplete"
FAST_BELOW, SLOW_ABOVE = 0.7, 1.5
INCOMPLETE_BELOW, OVERDONE_ABOVE = 0.7, 1.3


def guidance_for(tempo: float, reach: float) -> str:
    """The most important guidance type for a repetition, or "" when none applies."""
    if reach < INCOMPLETE_BELOW:
        return INCOMPLETE
    if reach > OVERDONE_ABOVE:
        return OVERDONE
    if tempo < FAST_BELOW:
        return TOO_FAST
    if tempo > SLOW_ABOVE:
        return TOO_SLOW
    return ""
