"""Clinical measures: anatomical joint angles in degrees, normal ranges, reachable workspace.

Public API:

- `angle_series(motion, method="orientation") -> dict[str, ndarray]`: degrees per frame for
  each angle of `ANGLE_NAMES` the skeleton gives (``knee_flexion_left`` … ``trunk_flexion``,
  ``trunk_lateral_flexion``; the interface contract's ``clinical_angles``).
- `angle_ranges(series, start=None, end=None) -> dict[str, AngleRange]`: min/max per angle over
  a recording or a repetition (frames ``start..end`` inclusive).
- `clinical_angles(motion) -> dict[str, AngleRange]`: both in one call, whole recording.
- `measure(motion) -> Measured(series, notes)`: the series of the angles the recording measures
  and, per other angle, why not (``clinical_notes``: a segment the skeleton lacks, or readings
  beyond the body's physiological limits, `LIMITS`).
- `Norm`, `NORMS`, `norm_for(name)`: normal adult active ranges (AAOS); `LIMITS`,
  `limits_for(name)`: what a body can reach; `bounded_amount(name, amount)`: a finding's or
  correction's amount bounded by that (`physiological_span`, compensations included).
- `Workspace`, `reachable_workspace(motion, start=None, end=None)`,
  `workspace_from_points(points, side)`: reachable workspace of each hand (relative surface
  area, total and per quadrant, and the hull for a 3D view).

Conventions and sources: docs/sections/clinical.md. Numpy, scipy and trimesh only.
"""

from analysis.clinical.angles import (
    ANGLE_NAMES,
    angle_ranges,
    angle_series,
    clinical_angles,
    measure,
)
from analysis.clinical.measured import Measured
from analysis.clinical.norms import (
    LIMITS,
    NORMS,
    Norm,
    bounded_amount,
    limits_for,
    norm_for,
    physiological_span,
)
from analysis.clinical.workspace import (
    QUADRANTS,
    Workspace,
    reachable_workspace,
    workspace_from_points,
)

__all__ = [
    "ANGLE_NAMES",
    "LIMITS",
    "NORMS",
    "QUADRANTS",
    "Measured",
    "Norm",
    "Workspace",
    "angle_ranges",
    "angle_series",
    "bounded_amount",
    "clinical_angles",
    "limits_for",
    "measure",
    "norm_for",
    "physiological_span",
    "reachable_workspace",
    "workspace_from_points",
]
