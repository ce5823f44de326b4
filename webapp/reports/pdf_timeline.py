"""The recording's timeline drawn for the PDF: repetitions with pass/fail, guidance and the three
key-pose layers (found, moved by refining, removed or added by periodic analysis), in seconds,
labelled in a therapist's words.

Takes the plain dict of `webapp.reports.timeline.timeline`.
"""

from __future__ import annotations

from typing import Any

from reportlab.graphics.shapes import Drawing, Line, Rect, String
from reportlab.lib import colors
from reportlab.lib.units import cm
from reportlab.pdfbase.pdfmetrics import stringWidth

WIDTH, LEFT, RIGHT = 17 * cm, 3.9 * cm, 16.7 * cm
ROW, GAP = 12, 5
TYPE_COLOURS = [colors.HexColor(c) for c in ("#0969da", "#bf3989", "#1a7f37", "#9a6700", "#8250df")]
PASSED, FAILED = colors.HexColor("#cde8d5"), colors.HexColor("#f6d2cf")
GUIDANCE, REMOVED, ADDED = (colors.HexColor(c) for c in ("#d4772c", "#cf222e", "#1a7f37"))
# Two lines under the axis: what the last three rows mean, in a therapist's words.
LEGEND = (
    "Exercise's order: x = key pose removed, + = key pose added, so the key poses come in the "
    "exercise's order.",
    "Adjusted key poses: moved to the nearest clear position. Colours: kinds of key pose.",
)
ROWS = ("Repetitions", "Guidance", "Key poses found", "Adjusted key poses", "Exercise's order")


def fitted(text: str, room: float, size: float = 7) -> str:
    """`text`, shortened with an ellipsis to fit `room` points ("" when nothing fits)."""
    if stringWidth(text, "Helvetica", size) <= room:
        return text
    while text and stringWidth(text + "…", "Helvetica", size) > room:
        text = text[:-1].rstrip()
    return text + "…" if len(text) >= 2 else ""


class _Canvas:
    def __init__(self, line: dict[str, Any]) -> None:
        self.line = line
        self.height = len(ROWS) * (ROW + GAP) + 76 + 9 * (len(LEGEND) - 1)
        self.drawing = Drawing(WIDTH, self.height)

    def x(self, percent: float) -> float:
        return LEFT + (RIGHT - LEFT) * percent / 100.0

    def y(self, row: int) -> float:
        return self.height - 22 - (row + 1) * (ROW + GAP)

    def span(self, row: int, item: dict[str, Any], fill, text: str, text_colour) -> None:
        x0, width = self.x(item["left"]), max((RIGHT - LEFT) * item["width"] / 100.0, 2.0)
        y = self.y(row)
        self.drawing.add(Rect(x0, y, width, ROW, fillColor=fill, strokeColor=None))
        shown = fitted(text, width - 4)
        if shown:
            self.drawing.add(String(x0 + 2, y + 3, shown, fontSize=7, fillColor=text_colour))

    def tick(self, row: int, item: dict[str, Any], fill, hollow: bool = False) -> None:
        x, y = self.x(item["left"]), self.y(row)
        self.drawing.add(
            Rect(x - 2.5, y, 5, ROW, fillColor=colors.white if hollow else fill,
                 strokeColor=fill, strokeWidth=1.2)
        )  # fmt: skip

    def glyph(self, row: int, item: dict[str, Any], text: str, fill) -> None:
        x, y = self.x(item["left"]), self.y(row)
        self.drawing.add(String(x, y + 2, text, fontSize=10, fillColor=fill, textAnchor="middle"))

    def axis(self) -> None:
        y = self.y(len(ROWS) - 1) - 6
        self.drawing.add(Line(LEFT, y, RIGHT, y, strokeColor=colors.grey, strokeWidth=0.6))
        for tick in self.line.get("ticks", ()):
            t, x = tick["seconds"], self.x(tick["left"])
            self.drawing.add(Line(x, y, x, y - 3, strokeColor=colors.grey, strokeWidth=0.6))
            self.drawing.add(String(x, y - 11, f"{t:g}", fontSize=7, textAnchor="middle"))
        self.drawing.add(String((LEFT + RIGHT) / 2, y - 21, "time (s)", fontSize=8,
                                textAnchor="middle"))  # fmt: skip
        for k, legend in enumerate(LEGEND):
            self.drawing.add(String(0, y - 33 - 9 * k, legend, fontSize=7, fillColor=colors.grey))


def type_colour(kind: int):
    return TYPE_COLOURS[(max(kind, 1) - 1) % len(TYPE_COLOURS)]


def timeline_drawing(line: dict[str, Any]) -> Drawing:
    canvas = _Canvas(line)
    d = canvas.drawing
    threshold = line["threshold"]
    d.add(String(0, canvas.height - 12, f"Timeline (pass needs a score of {threshold})",
                 fontSize=10))  # fmt: skip
    for row, label in enumerate(ROWS):
        d.add(String(0, canvas.y(row) + 3, label, fontSize=7.5))
    for rep in line["repetitions"]:
        word = "pass" if rep["passed"] else "fail"
        canvas.span(0, rep, PASSED if rep["passed"] else FAILED,
                    f"#{rep['number']} {word} {rep['score']}", colors.black)  # fmt: skip
        for g in rep["guidance"]:
            canvas.span(1, g, GUIDANCE, g["label"], colors.white)
    for mark in line["identified"]:
        canvas.tick(2, mark, type_colour(mark["type"]))
    for mark in line["refined"]:
        canvas.tick(3, mark, type_colour(mark["type"]), hollow=True)
    for mark in line["removed"]:
        canvas.glyph(4, mark, "x", REMOVED)
    for mark in line["inserted"]:
        canvas.glyph(4, mark, "+", ADDED)
    canvas.axis()
    return d
