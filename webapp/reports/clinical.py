"""The clinical measures section of the recording report (PDF and printable page): each
anatomical angle's smallest, largest value and range in degrees beside the normal adult range,
by body region, and each hand's reachable workspace. Plain data in `clinical_content`, reportlab
flowables in `clinical_flowables`."""

from __future__ import annotations

from typing import Any

from reportlab.lib import colors
from reportlab.lib.styles import getSampleStyleSheet
from reportlab.platypus import Paragraph, Table, TableStyle

from analysis.clinical.norms import SOURCE
from webapp.recordings.clinical import clinical_groups, workspace_rows

ANGLE_HEADER = ["Angle", "Smallest", "Largest", "Range", "Normal adult range"]
STYLES = getSampleStyleSheet()
GRID = TableStyle(
    [
        ("GRID", (0, 0), (-1, -1), 0.4, colors.grey),
        ("BACKGROUND", (0, 0), (-1, 0), colors.HexColor("#eef2f6")),
        ("FONTSIZE", (0, 0), (-1, -1), 9),
    ]
)


def deg(value: float | None) -> str:
    return "–" if value is None else f"{float(value):.0f}°"


def angle_table_rows(groups: list[dict[str, Any]]) -> list[list[str]]:
    """One row per angle, "Region: Left knee flexion", figures in degrees."""
    return [
        [
            f"{group['region']}: {row['label']}",
            deg(row["min"]),
            deg(row["max"]),
            deg(row["range"]),
            f"{deg(row['norm_min'])} to {deg(row['norm_max'])}",
        ]
        for group in groups
        for row in group["rows"]
    ]


def clinical_content(result, exercise=None) -> dict[str, Any]:
    """``clinical_angles`` (rows of the angle table) and ``clinical_workspace`` (per hand, with
    ``clinical_quadrants`` naming its quadrant columns)."""
    hands = workspace_rows(result)
    return {
        "clinical_angles": angle_table_rows(clinical_groups(result, exercise)),
        "clinical_workspace": [
            [hand["label"], f"{hand['percent']:.1f} %"]
            + [f"{q['percent']:.1f} %" for q in hand["quadrants"]]
            for hand in hands
        ],
        "clinical_quadrants": [q["label"] for q in hands[0]["quadrants"]] if hands else [],
    }


def _table(rows: list[list[str]]) -> Table:
    t = Table(rows, repeatRows=1)
    t.setStyle(GRID)
    return t


def _text(text: str, style: str = "BodyText") -> Paragraph:
    return Paragraph(text.replace("&", "&amp;").replace("<", "&lt;"), STYLES[style])


def clinical_flowables(content: dict[str, Any]) -> list[Any]:
    """The section's headings, notes and tables (nothing when the run measured no angle)."""
    story: list[Any] = []
    if content.get("clinical_angles"):
        story.append(_text("Joint angles (degrees)", "Heading2"))
        story.append(_text(f"Over the whole recording; normal adult ranges: {SOURCE}."))
        story.append(_table([ANGLE_HEADER, *content["clinical_angles"]]))
    if content.get("clinical_workspace"):
        story.append(_text("Reachable workspace (% of the front hemisphere)", "Heading2"))
        header = ["Hand", "Reachable area", *content.get("clinical_quadrants", [])]
        story.append(_table([header, *content["clinical_workspace"]]))
    return story
