"""Errors the analysis raises for input a person can fix; their messages are for therapists."""

from __future__ import annotations


class AnalysisInputError(ValueError):
    """The recording cannot be analysed as it is (the message says why, in plain words)."""


class SkeletonMismatchError(AnalysisInputError):
    """The recording's joints cannot be mapped onto the exercise model's skeleton."""


class RecordingTooShortError(AnalysisInputError):
    """The recording has too few frames to hold one repetition."""


class ModelVersionError(ValueError):
    """A saved exercise model was written by an incompatible version of this code."""
