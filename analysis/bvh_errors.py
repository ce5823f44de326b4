"""The error raised for malformed BVH input."""

from __future__ import annotations


class BVHError(ValueError):
    """A BVH file cannot be read; ``line`` is the 1-based line number of the problem, if known."""

    def __init__(self, message: str, line: int | None = None) -> None:
        self.reason = message
        self.line = line
        super().__init__(f"line {line}: {message}" if line is not None else message)
