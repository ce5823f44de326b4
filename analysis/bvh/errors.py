"""Errors for input a person can fix: a malformed BVH file, a skeleton that cannot be mapped, a
recording too short to analyse. Their messages are for therapists."""

from __future__ import annotations


class BVHError(ValueError):
    """A BVH file cannot be read; ``line`` is the 1-based line number of the problem, if known."""

    def __init__(self, message: str, line: int | None = None) -> None:
        self.reason = message
        self.line = line
        super().__init__(f"line {line}: {message}" if line is not None else message)


class AnalysisInputError(ValueError):
    """The recording cannot be analysed as it is (the message says why, in plain words)."""


class SkeletonMismatchError(AnalysisInputError):
    """The recording's joints cannot be mapped onto the exercise model's skeleton."""


class RecordingTooShortError(AnalysisInputError):
    """The recording has too few frames to hold one repetition."""
