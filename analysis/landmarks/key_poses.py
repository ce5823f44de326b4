"""Key poses (landmarks) of one recording in the one form every stage passes along.

Identification, refining, periodic analysis, the key-pose suggestion of a new reference, the
exercise model's reference key poses, labelled training recordings and the adjustment all hand
key poses over as `KeyPoses`; only the result served to the web app lists them one by one (with
where each came from, `analysis.pipeline.results.KeyPose`), because that is the JSON contract.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class KeyPoses:
    """Frames (n,) in increasing order and the tutor's key-pose type of each (n,), ≥ 1 (type 1
    starts a repetition): eq 5.23's χ and 5.27's χ̄ in paper 004."""

    frames: IntArray
    types: IntArray

    @classmethod
    def of(cls, frames: npt.ArrayLike, types: npt.ArrayLike) -> KeyPoses:
        """From any sequences of frames and types (lists, tuples, arrays) of the same length."""
        f = np.asarray(frames, dtype=np.int64).reshape(-1)
        t = np.asarray(types, dtype=np.int64).reshape(-1)
        if f.shape != t.shape:
            raise ValueError(f"{f.size} key-pose frames but {t.size} types")
        return cls(f, t)

    def __len__(self) -> int:
        return int(self.frames.size)

    def __iter__(self) -> Iterator[tuple[int, int]]:
        """(frame, type) pairs as Python ints, in time order."""
        return zip(self.frames.tolist(), self.types.tolist(), strict=True)

    def same_as(self, other: KeyPoses) -> bool:
        """The same frames with the same types."""
        return np.array_equal(self.frames, other.frames) and np.array_equal(self.types, other.types)
