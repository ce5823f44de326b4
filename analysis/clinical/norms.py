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

from analysis.assessment.compensations import LIMIT_DEG, span_of

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
        Norm("shoulder_elevation", 0.0, 180.0),  # flexion's and abduction's common maximum
        # horizontal abduction 45° behind the side, horizontal adduction 135° across
        Norm("shoulder_plane_of_elevation", -45.0, 135.0),
        Norm("shoulder_rotation", -90.0, 70.0),  # external 90°, internal 70°
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


# Physiological limits: values no adult body reaches, so a reading beyond them is the capture's
# error, not a measurement (analysis.clinical.angles.within_limits). The normal maxima above,
# widened to what healthy and hypermobile adults reach: knees and elbows hyperextend up to
# about 10–15° (the Beighton score counts more than 10° as hypermobility: Beighton, Solomon &
# Soskolne, Ann Rheum Dis 1973); deep squatting and kneeling reach about 155–165° knee flexion,
# 35–40° ankle dorsiflexion and 120–140° hip flexion (Hemmerich et al., "Hip, knee, and ankle
# kinematics of high range of motion activities of daily living", J Orthop Res 2006); passive
# hip flexion with the knee bent exceeds 140° (Kapandji, The Physiology of the Joints, vol. 2),
# and where a rig turns the pelvis with the lower back (Kinect) the reading adds some flexion of
# the lumbar spine, so 150°; the arm
# ends overhead at 180° of elevation, a little further with the spine extended; the side
# splits of trained dancers reach 90° hip abduction.
# The trunk is measured against the vertical, so bending down to the floor adds the hips' flexion
# to the spine's (80° thoracolumbar, AAOS): up to about 135°.
LIMITS_SOURCE = (
    "normal maxima (AAOS) widened to healthy and hypermobile adults' extremes: Beighton et al. "
    "1973, Hemmerich et al. 2006, Kapandji"
)
LIMITS: dict[str, tuple[float, float]] = {
    "knee_flexion": (-15.0, 165.0),
    "hip_flexion": (-40.0, 150.0),
    "hip_abduction": (-45.0, 90.0),
    "ankle_dorsiflexion": (-60.0, 45.0),
    "shoulder_flexion": (-70.0, 185.0),
    "shoulder_abduction": (-10.0, 185.0),
    "shoulder_elevation": (0.0, 185.0),
    # a direction, read over one whole turn (angles.plane_of_elevation): the arm can point any
    # way it is raised, so no reading of it is beyond the body; the norm flags the unusual ones
    "shoulder_plane_of_elevation": (-135.0, 225.0),
    "shoulder_rotation": (-120.0, 110.0),  # the normal rotations widened as for hypermobility
    "elbow_flexion": (-15.0, 160.0),
    "trunk_flexion": (-45.0, 135.0),
    "trunk_lateral_flexion": (-60.0, 60.0),
}


def limits_for(name: str) -> tuple[float, float]:
    """The physiological limits (degrees) of an angle, with or without its side."""
    return LIMITS[norm_for(name).angle]


def physiological_span(name: str) -> float:
    """The most (degrees) a named measure can change by in a body: a clinical angle's whole
    physiological range (`LIMITS`, with or without its side), or a compensation's
    (``trunk_rotation``, ``shoulder_hike_left`` …: `analysis.assessment.compensations.REACH`).

    Raises KeyError for a name that is neither."""
    if any(name.startswith(k) for k in LIMIT_DEG):
        return span_of(name)
    low, high = limits_for(name)
    return high - low


def bounded_amount(name: str, amount: float) -> float:
    """A finding's or correction's amount (degrees of the named angle or compensation) bounded
    by what the body can do: never more than the measure's `physiological_span`, never below
    0 (a correction is a size)."""
    return min(max(float(amount), 0.0), physiological_span(name))
