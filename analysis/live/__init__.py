"""Live sessions, one frame at a time, without any network: the per-session aligner (where the
patient is in the tutor's movement, each repetition's score and guidance as it ends) and the
session protocol (messages in, events out).

Above `analysis.pipeline`: a live repetition is scored and given guidance by the exercise model
and the offline pipeline's rules, so a patient hears live what the recording's page later says.
The server (`webapp.live`) and the capture client (`capture`) drive it; neither lives here.
"""

from analysis.live.aligner import LiveAligner, LiveOptions, rehearse
from analysis.live.session import LiveSession, ProtocolError, RateLimit, header_text
from analysis.live.words import Event, repetition_words

__all__ = [
    "Event",
    "LiveAligner",
    "LiveOptions",
    "LiveSession",
    "ProtocolError",
    "RateLimit",
    "header_text",
    "rehearse",
    "repetition_words",
]
