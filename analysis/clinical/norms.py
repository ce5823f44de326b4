"""Normal adult active ranges of motion, per anatomical angle (degrees).

Values of the American Academy of Orthopaedic Surgeons (Greene & Heckman, *The Clinical
Measurement of Joint Motion*, AAOS 1994), as tabulated by Norkin & White, *Measurement of Joint
Motion: A Guide to Goniometry* (5th ed., F.A. Davis 2016). ``minimum`` is the opposite motion
with our signs (extension, adduction, plantar flexion, lateral flexion to the left: negative);
0 where the table gives none. Normal ranges vary with age and sex by 10–20°: the norm says what
a typical adult reaches, not a pass mark.
"""

from __future__ import annotations

from dataclasses import dataclass

SOURCE = "AAOS (Greene & Heckman 1994), via Norkin & White 2016"


@dataclass(frozen=True)
class Norm:
    """Normal active range of one angle: from ``minimum`` to ``maximum`` degrees."""

    angle: str  # name without side, e.g. "knee_flexion"
    minimum: float
    maximum: float
    source: str = SOURCE

    @property
    def range(self) -> float:
        return self.maximum - self.minimum

    def percent_of_maximum(self, value: float) -> float:
        """A reached value as a percentage of the normal maximum (e.g. 90° knee flexion: 67)."""
        return 100.0 * value / self.maximum


NORMS: dict[str, Norm] = {
    norm.angle: norm
    for norm in (
        Norm("knee_flexion", 0.0, 135.0),
        Norm("hip_flexion", -30.0, 120.0),
        Norm("hip_abduction", -30.0, 45.0),
        Norm("ankle_dorsiflexion", -50.0, 20.0),
        Norm("shoulder_flexion", -60.0, 180.0),
        Norm("shoulder_abduction", 0.0, 180.0),
        Norm("elbow_flexion", 0.0, 150.0),
        Norm("trunk_flexion", -25.0, 80.0),
        Norm("trunk_lateral_flexion", -35.0, 35.0),
    )
}


def norm_for(name: str) -> Norm:
    """The norm of an angle, with or without its side (``knee_flexion_left``, ``knee_flexion``).

    Raises KeyError for a name that is not a clinical angle.
    """
    for suffix in ("_left", "_right"):
        if name.endswith(suffix):
            name = name[: -len(suffix)]
    return NORMS[name]
