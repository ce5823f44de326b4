"""Which clinical angles a correction may be about, before the tutor's movement says which of
them the exercise trains (`analysis.assessment.findings.involved_angles`).

- The direction the arm is raised in (``shoulder_plane_of_elevation``) is shown with the angles
  and never corrected: it is a direction, not an excursion.
- The upper arm's rotation about itself (``shoulder_rotation``) is trained only where the tutor
  turns the arm `ROLL_LEAD` times as far as it moves anything else (UI-PRMD m09: 150° against its
  next angle's 30°), never where the arms turn while held or swinging for balance (UI-PRMD's
  straight-leg raise turns the hanging arms 60–80° under a hip that moves 100°).
"""

from __future__ import annotations

from collections.abc import Mapping

NOT_CORRECTED = ("shoulder_plane_of_elevation",)
ROLL, ROLL_LEAD = "shoulder_rotation", 1.5


def trainable(tutor: Mapping[str, float]) -> dict[str, float]:
    """The tutor's ranges (degrees) of the angles a correction may be about."""
    kept = {n: v for n, v in tutor.items() if not n.startswith(NOT_CORRECTED)}
    return {n: v for n, v in kept.items() if not n.startswith(ROLL) or _leads(n, kept)}


def _leads(name: str, tutor: Mapping[str, float]) -> bool:
    others = [v for n, v in tutor.items() if n != name]
    return tutor[name] >= ROLL_LEAD * max(others, default=0.0)
