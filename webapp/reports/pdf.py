"""PDF reports drawn with reportlab and its native charts (no system libraries).

`recording_pdf` describes one analysed recording; `progress_pdf` one patient over a period.
Both take plain data (built by `webapp.reports.content`) so they are easy to test.
"""

from __future__ import annotations

import io
from datetime import date, timedelta
from typing import Any

import numpy as np
from reportlab.graphics.charts.barcharts import VerticalBarChart
from reportlab.graphics.charts.lineplots import LinePlot
from reportlab.graphics.shapes import Circle, Drawing, Group, Line, String
from reportlab.graphics.widgets.markers import makeMarker
from reportlab.lib import colors
from reportlab.lib.pagesizes import A4
from reportlab.lib.styles import getSampleStyleSheet
from reportlab.lib.units import cm
from reportlab.platypus import (
    CondPageBreak,
    Paragraph,
    SimpleDocTemplate,
    Spacer,
    Table,
    TableStyle,
)

from webapp.recordings.words import LEVEL_HELP
from webapp.reports.clinical import clinical_flowables
from webapp.reports.pdf_timeline import timeline_drawing

STYLES = getSampleStyleSheet()
GRID = TableStyle(
    [
        ("GRID", (0, 0), (-1, -1), 0.4, colors.grey),
        ("BACKGROUND", (0, 0), (-1, 0), colors.HexColor("#eef2f6")),
        ("FONTSIZE", (0, 0), (-1, -1), 9),
    ]
)
PALETTE = [colors.HexColor(c) for c in ("#1f6feb", "#2da44e", "#8250df", "#d4772c", "#cf222e")]


def paragraph(text: str, style: str = "BodyText") -> Paragraph:
    escaped = str(text).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    return Paragraph(escaped, STYLES[style])


def small(text: str) -> Paragraph:
    """A table cell that wraps (9 pt, as the grid's text)."""
    escaped = str(text).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    return Paragraph(f'<font size="9">{escaped}</font>', STYLES["BodyText"])


def table(rows: list[list[Any]], widths: list[float] | None = None) -> Table:
    cells = [[c if isinstance(c, Paragraph) else str(c) for c in row] for row in rows]
    t = Table(cells, colWidths=widths, repeatRows=1)
    t.setStyle(GRID)
    return t


def bar_chart(values: list[float], labels: list[str], title: str) -> Drawing:
    drawing = Drawing(16 * cm, 6 * cm)
    chart = VerticalBarChart()
    chart.x, chart.y, chart.width, chart.height = 40, 30, 14 * cm, 4 * cm
    chart.data = [values or [0]]
    chart.categoryAxis.categoryNames = labels or [""]
    chart.valueAxis.valueMin, chart.valueAxis.valueMax = 0, 100
    chart.bars[0].fillColor = PALETTE[0]
    drawing.add(chart)
    drawing.add(String(40, 6 * cm - 12, title, fontSize=10))
    drawing.add(String(40 + 6 * cm, 4, "repetition (number)", fontSize=8))
    drawing.add(String(4, 30 + 4 * cm + 6, "score (0–100)", fontSize=8))
    return drawing


CHART_W, CHART_H = 16 * cm, 8 * cm
PLOT_LEFT, PLOT_BOTTOM = 52, 40  # room for the tick labels, the axis titles beside them
LEGEND_TOP = 26  # from the top: under the title, above the plot
MAX_TICKS = 8


def day_ticks(first: float, last: float) -> list[float]:
    """Tick places at the middle of whole days (at most MAX_TICKS), so labels name days."""
    lo, hi = int(first // 1), int(last // 1)
    step = max(1, -(-(hi - lo + 1) // MAX_TICKS))
    return [day + 0.5 for day in range(lo, hi + 1, step)]


def line_chart(
    series: dict[str, list[tuple[float, float]]],
    title: str,
    y_title: str,
    first_day: date | None,
    y_range: tuple[float, float] | None = None,
) -> Drawing:
    """One line per series over the session dates (x: days since `first_day`, labelled
    "12 Nov"); the title on top, the legend (up to four, two per row) under it, the plot below,
    the y title turned along the axis and the x title under the dates: nothing overlaps."""
    drawing = Drawing(CHART_W, CHART_H)
    names = [name for name, points in series.items() if points]
    legend_rows = (min(len(names), 4) + 1) // 2
    plot = LinePlot()
    plot.x, plot.y = PLOT_LEFT, PLOT_BOTTOM
    plot.width = CHART_W - PLOT_LEFT - 12
    plot.height = CHART_H - PLOT_BOTTOM - LEGEND_TOP - 12 * legend_rows - 8
    plot.data = [series[name] for name in names] or [[(0.5, 0)]]
    xs = [x for line in plot.data for x, _ in line]
    plot.xValueAxis.valueMin = min(xs) // 1 - 0.25
    plot.xValueAxis.valueMax = max(xs) // 1 + 1.25
    plot.xValueAxis.valueSteps = day_ticks(min(xs), max(xs))
    start = first_day or date.today()
    plot.xValueAxis.labelTextFormat = lambda x: f"{start + timedelta(days=int(x)):%-d %b}"
    plot.xValueAxis.labels.fontSize = plot.yValueAxis.labels.fontSize = 8
    plot.yValueAxis.valueMin = 0  # scores and ranges of motion start at nothing
    if y_range:
        plot.yValueAxis.valueMin, plot.yValueAxis.valueMax = y_range
    for i in range(len(plot.data)):
        plot.lines[i].strokeColor = PALETTE[i % len(PALETTE)]
        plot.lines[i].strokeWidth = 1.5
        plot.lines[i].symbol = _marker(PALETTE[i % len(PALETTE)])
    drawing.add(plot)
    drawing.add(String(PLOT_LEFT, CHART_H - 12, title, fontSize=10))
    drawing.add(String(PLOT_LEFT + plot.width / 2, 4, "date of the session", fontSize=8,
                       textAnchor="middle"))  # fmt: skip
    drawing.add(_turned(y_title, 10, PLOT_BOTTOM + plot.height / 2))
    for i, name in enumerate(names[:4]):
        x = PLOT_LEFT + (i % 2) * (plot.width / 2)
        y = CHART_H - LEGEND_TOP - 12 * (i // 2)
        drawing.add(Line(x, y + 3, x + 14, y + 3, strokeColor=PALETTE[i], strokeWidth=1.5))
        drawing.add(String(x + 18, y, name[:40], fontSize=8))
    return drawing


def _marker(color: colors.Color) -> Any:
    marker = makeMarker("FilledCircle")
    marker.size, marker.fillColor, marker.strokeColor = 3, color, color
    return marker


def _turned(text: str, x: float, y: float) -> Group:
    """A y-axis title written upwards along the axis, centred on (x, y)."""
    group = Group(String(0, 0, text, fontSize=8, textAnchor="middle"))
    group.transform = (0, 1, -1, 0, x, y)
    return group


def pose_drawing(poses: list[tuple[str, np.ndarray]], parents: list[int]) -> Drawing:
    """Stick figures (front view, x and y) of key poses side by side: (J, 3) each."""
    width, height = 16 * cm, 5 * cm
    drawing = Drawing(width, height)
    slot = width / max(len(poses), 1)
    for i, (label, pose) in enumerate(poses):
        xy = pose[:, :2]
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        scale = 0.8 * min(slot, height - 20) / max(float((hi - lo).max()), 1e-6)
        cx = i * slot + slot / 2 - scale * (lo[0] + hi[0]) / 2
        pts = [(cx + scale * x, 14 - scale * lo[1] + scale * y) for x, y in xy]
        for j, p in enumerate(parents):
            if p >= 0:
                drawing.add(Line(*pts[p], *pts[j], strokeColor=PALETTE[0], strokeWidth=1.4))
        for x, y in pts:
            drawing.add(Circle(x, y, 1.2, fillColor=colors.black, strokeColor=None))
        drawing.add(String(i * slot + 4, 2, label[:24], fontSize=7))
    return drawing


def build(story: list[Any], title: str) -> bytes:
    buffer = io.BytesIO()
    doc = SimpleDocTemplate(
        buffer,
        pagesize=A4,
        title=title,
        author="Physio dashboard",
        leftMargin=2 * cm,
        rightMargin=2 * cm,
        topMargin=1.8 * cm,
        bottomMargin=1.8 * cm,
    )
    doc.build(story)
    return buffer.getvalue()


def recording_pdf(content: dict[str, Any]) -> bytes:
    story: list[Any] = [paragraph(content["title"], "Title")]
    story += [paragraph(line) for line in content["header"]]
    story.append(Spacer(1, 0.4 * cm))
    if not content.get("analysed"):
        story.append(paragraph("This recording has no analysis result yet."))
        return build(story + notes_flowables(content), content["title"])
    story.append(paragraph(f"Score {content['score']} / 100", "Heading2"))
    if content.get("passed_line"):  # the run's reading: the same count as every page
        story.append(paragraph(content["passed_line"]))
    reps = content["repetitions"]
    story.append(
        table([["#", "Time (s)", "Score (0–100)", "Result", "Guidance"],
               *[[*r[:3], small(r[3]), small(r[4])] for r in reps]],
              widths=[0.8 * cm, 2.2 * cm, 2.4 * cm, 5 * cm, 6.6 * cm])
    )  # fmt: skip
    line = content.get("timeline")
    if line:
        if line.get("fallback"):
            story.append(paragraph(line["fallback_note"]))
        story.append(Spacer(1, 0.2 * cm))
        story.append(timeline_drawing(line))
    story.append(
        bar_chart(
            [float(r[2]) for r in reps], [str(r[0]) for r in reps],
            "Score per repetition (0–100)",
        )
    )  # fmt: skip
    story.append(paragraph("Feedback", "Heading2"))
    story += [paragraph(f"• {text}") for text in content["feedback"]] or [paragraph("No remarks.")]
    if content.get("poses"):
        story.append(paragraph("Key poses", "Heading2"))
        story.append(pose_drawing(content["poses"], content["parents"]))
    if content.get("rom"):
        # body segments' own turning, not the clinical angles (those are the table of angles)
        story.append(paragraph("Body segments: how far each turned, and its level", "Heading2"))
        head = ["Body segment", "Turned (degrees)", "Level (0–1)"]
        story.append(table([head, *content["rom"]]))
        story.append(paragraph(LEVEL_HELP))
    story += clinical_flowables(content)
    story += notes_flowables(content)
    return build(story, content["title"])


def notes_flowables(content: dict[str, Any]) -> list[Any]:
    """The recording's clinical notes, each signed and dated (nothing when there is none)."""
    if not content.get("notes"):
        return []
    story: list[Any] = [paragraph("Clinical notes", "Heading2")]
    for note in content["notes"]:
        story.append(paragraph(f"{note['author']}, {note['date']}:", "Italic"))
        story.append(paragraph(note["text"]))
    return story


def goals_flowables(content: dict[str, Any]) -> list[Any]:
    """The patient's goals with their latest value and whether each is met or on track."""
    if not content.get("goals"):
        return []
    head = ["Exercise", "Goal", "Latest", "Status"]
    rows = [[small(cell) for cell in row] for row in content["goals"]]
    widths = [3.2 * cm, 8.2 * cm, 2 * cm, 3.6 * cm]
    return table_section("Goals", table([head, *rows], widths=widths))


def progress_pdf(content: dict[str, Any]) -> bytes:
    story: list[Any] = [paragraph(content["title"], "Title")]
    story += [paragraph(line) for line in content["header"]]
    story.append(Spacer(1, 0.4 * cm))
    rows = content["rows"]
    if not rows:
        story.append(paragraph("No analysed recordings in this period."))
        return build(story + goals_flowables(content), content["title"])
    first = content.get("first_day")
    story.append(
        line_chart(content["score_series"], "Score by session", "score (0–100)", first, (0, 100))
    )
    for exercise, series in content["rom_series"].items():
        if series:
            title = f"{exercise}: range of the joint angles moved most, by session"
            story.append(line_chart(series, title, "range of motion (°)", first))
            story.append(paragraph(content.get("rom_norms", {}).get(exercise, "")))
    head = ["Date", "Exercise", "Score (0–100)", "Repetitions", "Pain (0–10)"]
    story += table_section("Sessions", table([head, *rows]))
    story += goals_flowables(content)
    return build(story, content["title"])


def table_section(heading: str, body: Table) -> list[Any]:
    """A heading and its table that never start with a lone row at a page's foot: a new page
    unless a good part of the table fits there (the header row repeats on every page)."""
    return [CondPageBreak(6 * cm), paragraph(heading, "Heading2"), body]
