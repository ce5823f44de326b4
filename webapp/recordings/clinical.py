"""Clinical measures of one analysed recording, as the recording page and the reports show them.

Plain words and degrees only (``analysis.clinical.labels``): each angle's min, max and range
beside the normal adult range (values outside it flagged), grouped by body region with the
regions the exercise moves first, and the angles the recording could not measure with the reason;
left and right ranges side by side; per repetition the range of the angles the exercise moves;
and each hand's reachable workspace.
"""

from __future__ import annotations

from typing import Any

from analysis.clinical.labels import QUADRANT_LABELS, angle_groups, angle_label, symmetry_rows
from analysis.pipeline.results import AnalysisSummary

SIDE_LABELS = {"left": "Left hand", "right": "Right hand"}
MOVING_DEGREES = 10.0  # per-repetition table without an involved region: angles moving this much


def involved_joints(exercise) -> list[str]:
    return list(getattr(exercise, "involved_joints", None) or [])


def clinical_groups(result: AnalysisSummary | None, exercise=None) -> list[dict[str, Any]]:
    if result is None:
        return []
    return angle_groups(result.clinical_angles, involved_joints(exercise), result.clinical_notes)


def _per_repetition_names(groups: list[dict[str, Any]]) -> list[str]:
    involved = [row["name"] for g in groups if g["involved"] for row in g["rows"]]
    if involved:
        return involved
    return [row["name"] for g in groups for row in g["rows"] if row["range"] >= MOVING_DEGREES]


def repetition_table(result: AnalysisSummary | None, groups: list[dict[str, Any]]) -> dict:
    """``{"repetitions": [1, 2, …], "rows": [{"label", "ranges": [deg or None, …]}]}`` for the
    angles the exercise moves; empty when the run stored no per-repetition angles."""
    if result is None or not any(rep.clinical_angles for rep in result.repetitions):
        return {}
    rows = []
    for name in _per_repetition_names(groups):
        ranges = [rep.clinical_angles.get(name) for rep in result.repetitions]
        rows.append({"label": angle_label(name), "ranges": [r and r.range for r in ranges]})
    numbers = list(range(1, len(result.repetitions) + 1))
    return {"repetitions": numbers, "rows": rows} if rows else {}


def workspace_rows(result: AnalysisSummary | None) -> list[dict[str, Any]]:
    """Per hand: its label, the reachable area and each quadrant's in % of the front hemisphere
    (each quadrant is at most 25 %)."""
    if result is None:
        return []
    return [
        {
            "side": side,
            "label": SIDE_LABELS.get(side, side),
            "percent": round(100.0 * ws.relative_area, 1),
            "quadrants": [
                {"label": QUADRANT_LABELS.get(q, q), "percent": round(100.0 * v, 1)}
                for q, v in ws.quadrants.items()
            ],
        }
        for side, ws in sorted(result.workspace.items())
    ]


def workspace_hulls(result: AnalysisSummary | None) -> list[dict[str, Any]]:
    """The small hulls for the 3D view: ``[{"side", "label", "vertices", "faces"}]``."""
    if result is None:
        return []
    return [
        {
            "side": side,
            "label": SIDE_LABELS.get(side, side),
            "vertices": [list(v) for v in ws.vertices],
            "faces": [list(f) for f in ws.faces],
        }
        for side, ws in sorted(result.workspace.items())
        if ws.faces
    ]


def clinical_context(result: AnalysisSummary | None, exercise=None) -> dict[str, Any]:
    groups = clinical_groups(result, exercise)
    return {
        "groups": groups,
        "symmetry": symmetry_rows(result.clinical_angles) if result is not None else [],
        "per_repetition": repetition_table(result, groups),
        "workspace": workspace_rows(result),
        "hulls": workspace_hulls(result),
    }
