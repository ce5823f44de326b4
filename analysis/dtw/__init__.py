"""Offline time warping: options, compiled kernels, frame costs with joint
weights, CMA-ES joint weights, and the alignment and similarity metrics.

Pipeline: repetition scoring aligns each repetition with every tutor repetition through
`nearest.closest_paths` (`align` for each pair, in one compiled call).
"""

from analysis.dtw.frame_costs import (
    CostInputs,
    as_frames,
    cost_matrix,
    cost_rows,
    is_quaternion_kind,
    paired_costs,
    path_groups,
    speed_insensitive_cost,
)
from analysis.dtw.offline import Alignment, DTWOptions, align

__all__ = [
    "Alignment",
    "CostInputs",
    "DTWOptions",
    "align",
    "as_frames",
    "cost_matrix",
    "cost_rows",
    "is_quaternion_kind",
    "paired_costs",
    "path_groups",
    "speed_insensitive_cost",
]
