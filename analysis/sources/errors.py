"""The error an unreadable capture file raises: a `BVHError` subclass, so every caller that
already shows a BVH reading problem in plain words shows this one too."""

from __future__ import annotations

from analysis.bvh.errors import BVHError


class CaptureFileError(BVHError):
    """A joint-position or marker file cannot be read (one plain sentence, no line number)."""
