"""Repetitions from a cleaned periodic landmark sequence (thesis 004, 5.4.1 and chapter 6).

The tutor's *order* gives the landmark types of one repetition as a cycle whose first type is
the *start* (rest pose) that also closes the repetition: ``[1, 2]`` is start → end of range →
next start (``[1, 2, 1]``, the period as ``periodic.clean`` takes it, means the same). An
exercise done on both sides gives one cycle per side, ``[[1, 2], [3, 4]]``.

What counts as a repetition:

- It opens at a landmark of a cycle's start type and runs to the next start-type landmark of
  the same cycle, which closes it and opens the next one (the two share that frame, as in
  ``data/ui-prmd/landmarks.csv``).
- It is *complete* when it was opened and closed by its start type and its intermediate types,
  with immediate repeats collapsed (two end-of-range detections in a row count once, both frames
  are kept), are exactly the cycle's, in order. Anything else is kept and marked incomplete:
  a repetition cut short by a start of another cycle or by the end of the recording, one whose
  opening start is missing (its start is then the previous landmark's frame, or 0), or one
  with missing or out-of-order intermediate landmarks.
- A start followed directly by another start (no intermediate landmark) is not a repetition:
  nothing was detected between two rest poses.
- Patients may do more or fewer repetitions than the tutor (eq 5.12): all are returned. They may
  also do the sides in another order, alternate them, or do right before left (eq 5.13):
  repetitions are matched by landmark type, never by position in the tutor's sequence.
- A landmark of another cycle's intermediate type inside a repetition (no start of that cycle
  before it) ends the current repetition, incomplete, and opens one of the other cycle whose
  start is missing.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import pairwise
from numbers import Integral
from typing import cast


@dataclass(frozen=True)
class Repetition:
    """One repetition; frames are indices into the recording.

    start: first frame. peaks: frames of its intermediate landmarks (e.g. end of range), in
    time order, with their types in ``peak_types``. end: last frame (the closing start, the
    landmark that cut it short, or the end of the recording). complete: see the module doc.
    cycle: index of the tutor's cycle (e.g. 0 = left side, 1 = right side).
    """

    start: int
    peaks: tuple[int, ...]
    end: int
    complete: bool
    cycle: int
    peak_types: tuple[int, ...] = ()


@dataclass
class _Open:
    """The repetition being read."""

    cycle: int
    start: int
    opened: bool  # began with its start-type landmark
    peaks: list[tuple[int, int]] = field(default_factory=list)


def _cycles(order: Sequence[int] | Sequence[Sequence[int]]) -> list[tuple[int, ...]]:
    """The tutor's cycles, validated: non-empty, each type in one cycle only."""
    items = list(order)
    if items and all(isinstance(t, Integral) for t in items):
        cycles = [tuple(int(t) for t in cast(list[int], items))]
    else:
        cycles = [tuple(int(t) for t in c) for c in cast(list[Sequence[int]], items)]
    # a closed cycle, as a training period is written ([1, 2, 1]), is the same cycle
    cycles = [c[:-1] if len(c) > 1 and c[-1] == c[0] else c for c in cycles]
    seen: set[int] = set()
    for cycle in cycles:
        if not cycle or len(set(cycle)) != len(cycle) or seen & set(cycle):
            raise ValueError("each cycle needs distinct types, and each type one cycle")
        seen |= set(cycle)
    if not cycles:
        raise ValueError("order must hold at least one cycle")
    return cycles


def _finish(rep: _Open, end: int, closed: bool, cycle: tuple[int, ...]) -> Repetition | None:
    """The repetition ``rep`` ending at ``end``; None when it holds no intermediate landmark."""
    if not rep.peaks:
        return None
    types = [t for _, t in rep.peaks]
    collapsed = tuple(t for i, t in enumerate(types) if i == 0 or t != types[i - 1])
    complete = rep.opened and closed and collapsed == cycle[1:]
    return Repetition(
        start=rep.start,
        peaks=tuple(f for f, _ in rep.peaks),
        end=end,
        complete=complete,
        cycle=rep.cycle,
        peak_types=tuple(types),
    )


def repetitions(
    frames: Sequence[int],
    types: Sequence[int],
    order: Sequence[int] | Sequence[Sequence[int]],
    last_frame: int | None = None,
) -> list[Repetition]:
    """Repetitions of a cleaned landmark sequence, in time order.

    frames: (L,) landmark frames, non-decreasing. types: (L,) their landmark types, each one of
    ``order``'s. order: one cycle (``[1, 2]``) or one per side (``[[1, 2], [3, 4]]``).
    last_frame: the recording's last frame, the end of a repetition left open at the end
    (default: its last landmark). Raises ValueError on mismatched lengths, unsorted frames or
    unknown types.
    """
    cycles = _cycles(order)
    where = {t: (c, i) for c, cycle in enumerate(cycles) for i, t in enumerate(cycle)}
    frames, types = [int(f) for f in frames], [int(t) for t in types]  # numpy ints welcome
    _check(frames, types, where)
    out: list[Repetition] = []
    rep: _Open | None = None
    previous = 0
    for frame, kind in zip(frames, types, strict=True):
        c, position = where[kind]
        if rep is not None and (position == 0 or rep.cycle != c):
            closed = position == 0 and rep.cycle == c
            done = _finish(rep, frame, closed, cycles[rep.cycle])
            out += [done] if done else []
            rep = None
        if rep is None:
            rep = _Open(c, frame if position == 0 else previous, position == 0)
        if position > 0:
            rep.peaks.append((frame, kind))
        previous = frame
    if rep is not None:
        end = last_frame if last_frame is not None else previous
        done = _finish(rep, end, False, cycles[rep.cycle])
        out += [done] if done else []
    return out


def _check(frames: Sequence[int], types: Sequence[int], where: dict[int, tuple[int, int]]) -> None:
    if len(frames) != len(types):
        raise ValueError(f"{len(frames)} frames but {len(types)} types")
    if any(b < a for a, b in pairwise(frames)):
        raise ValueError("landmark frames must be in time order")
    unknown = sorted({t for t in types if t not in where})
    if unknown:
        raise ValueError(f"landmark types {unknown} are in no cycle of the tutor's order")
