"""The clinical measures section of the recording report (PDF and printable page): each
anatomical angle's smallest, largest value and range in degrees beside the normal adult range
(values outside it flagged), by body region, the angles the recording could not measure with the
reason, left and right ranges side by side, and each hand's reachable workspace. Plain data in
`clinical_content`, reportlab flowables in `clinical_flowables`."""

from __future__ import annotations

from typing import Any

from reportlab.lib import colors
from reportlab.lib.styles import ParagraphStyle, getSampleStyleSheet
from reportlab.platypus import Paragraph, Table, TableStyle

from analysis.clinical.labels import symmetry_rows
from analysis.clinical.norms import SOURCE
from webapp.recordings.clinical import clinical_groups, workspace_rows

ANGLE_HEADER = ["Angle", "Smallest", "Largest", "Range", "Normal adult range"]
SYMMETRY_HEADER = ["Movement", "Left", "Right", "Left minus right"]
STYLES = getSampleStyleSheet()
STYLES.add(ParagraphStyle("small", parent=STYLES["BodyText"], fontSize=9, leading=11))
GRID = TableStyle(
    [
        ("GRID", (0, 0), (-1, -1), 0.4, colors.grey),
        ("BACKGROUND", (0, 0), (-1, 0), colors.HexColor("#eef2f6")),
        ("FONTSIZE", (0, 0), (-1, -1), 9),
    ]
)


def deg(value: float | None) -> str:
    return "–" if value is None else f"{float(value):.0f}°"


def _normal(row: dict[str, Any]) -> str:
    normal = f"{deg(row['norm_min'])} to {deg(row['norm_max'])}"
    return f"{normal}: {row['flag']}" if row.get("flag") else normal


def angle_table_rows(groups: list[dict[str, Any]]) -> list[list[str]]:
    """One row per angle, "Region: Left knee flexion", figures in degrees, the normal range
    with a flag when the recording leaves it; then each angle not measured, with why (in the
    second cell, the others empty)."""
    rows = []
    for group in groups:
        for row in group["rows"]:
            rows.append([
                f"{group['region']}: {row['label']}", deg(row["min"]), deg(row["max"]),
                deg(row["range"]), _normal(row),
            ])  # fmt: skip
        for note in group.get("notes", ()):
            rows.append([f"{group['region']}: {note['label']}", note["note"], "", "", ""])
    return rows


def symmetry_table_rows(result) -> list[list[str]]:
    """Each movement measured on both sides: its left and right ranges and their difference."""
    if result is None:
        return []
    return [
        [row["label"], deg(row["left"]), deg(row["right"]), deg(row["difference"])]
        for row in symmetry_rows(result.clinical_angles)
    ]


def clinical_content(result, exercise=None) -> dict[str, Any]:
    """``clinical_angles`` (rows of the angle table) and ``clinical_workspace`` (per hand, with
    ``clinical_quadrants`` naming its quadrant columns)."""
    hands = workspace_rows(result)
    return {
        "clinical_angles": angle_table_rows(clinical_groups(result, exercise)),
        "clinical_symmetry": symmetry_table_rows(result),
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


def _angle_table(rows: list[list[str]]) -> Table:
    """The angle table; a row of an angle not measured spans its reason over the figures."""
    wrapped = [(k, i) for k, r in enumerate(rows) if k for i in ((1,) if not r[2] else (0, 4))]
    cells = [list(r) for r in rows]
    for k, i in wrapped:  # long words wrap inside their cell
        cells[k][i] = _text(rows[k][i], "small")
    t = Table(cells, repeatRows=1, colWidths=[140, 55, 55, 55, 175])
    spans = [("SPAN", (1, k), (4, k)) for k, r in enumerate(rows) if k and not r[2]]
    t.setStyle(TableStyle([*GRID.getCommands(), *spans]))
    return t


def _text(text: str, style: str = "BodyText") -> Paragraph:
    return Paragraph(text.replace("&", "&amp;").replace("<", "&lt;"), STYLES[style])


def clinical_flowables(content: dict[str, Any]) -> list[Any]:
    """The section's headings, notes and tables (nothing when the run measured no angle)."""
    story: list[Any] = []
    if content.get("clinical_angles"):
        story.append(_text("Joint angles (degrees)", "Heading2"))
        story.append(_text(f"Over the whole recording; normal adult ranges: {SOURCE}."))
        story.append(_angle_table([ANGLE_HEADER, *content["clinical_angles"]]))
    if content.get("clinical_symmetry"):
        story.append(_text("Left and right (range in degrees)", "Heading2"))
        story.append(_table([SYMMETRY_HEADER, *content["clinical_symmetry"]]))
    if content.get("clinical_workspace"):
        story.append(_text("Reachable workspace (% of the front hemisphere)", "Heading2"))
        header = ["Hand", "Reachable area", *content.get("clinical_quadrants", [])]
        story.append(_table([header, *content["clinical_workspace"]]))
    return story
