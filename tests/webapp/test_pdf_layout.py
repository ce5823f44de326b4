"""The PDF reports' layout (issue 23, item 6): no two pieces of text overlap on any page (chart
titles, axis titles, legends, tick labels, tables), no page is blank, the progress report's
x-axes are dates and its tables do not break after one row.

Text is read with pdfminer.six character by character (a line it merges could hide an overlap);
pages are rendered with pypdfium2 (a wheel from PyPI: no system program needed)."""

from __future__ import annotations

import datetime
import io
import re

import numpy as np
import pypdfium2
import pytest
from django.utils import timezone
from pdfminer.high_level import extract_pages
from pdfminer.layout import LAParams, LTChar, LTTextContainer, LTTextLine

from tests.personas import make_exercise
from tests.webapp.test_clinical_pages import analysed, squat_angles, summary
from tests.webapp.test_progress_charts import session
from webapp.patients.models import Goal
from webapp.recordings.models import Recording
from webapp.reports.content import progress_content, recording_content
from webapp.reports.pdf import progress_pdf, recording_pdf

TOLERANCE = 1.0  # points: glyph boxes of neighbouring letters may touch


def text_lines(pdf: bytes) -> list[list[tuple[str, list[tuple[float, ...]]]]]:
    """Per page, each text line with the boxes of its characters (upright and turned text)."""
    pages = []
    for layout in extract_pages(io.BytesIO(pdf), laparams=LAParams(detect_vertical=True)):
        lines = []
        for box in layout:
            if isinstance(box, LTTextContainer):
                for line in box:
                    if isinstance(line, LTTextLine):
                        chars = [
                            c.bbox for c in line if isinstance(c, LTChar) and c.get_text().strip()
                        ]
                        lines.append((line.get_text().strip(), chars))
        pages.append(lines)
    return pages


def overlaps(lines: list[tuple[str, list[tuple[float, ...]]]]) -> list[tuple[str, str]]:
    """Pairs of texts with characters whose boxes intersect by more than TOLERANCE each way."""
    owners = [text for text, chars in lines for _ in chars]
    boxes = np.array([c for _, chars in lines for c in chars], dtype=float).reshape(-1, 4)
    x0, y0, x1, y1 = (boxes[:, i] for i in range(4))
    wide = np.minimum(x1[:, None], x1[None, :]) - np.maximum(x0[:, None], x0[None, :])
    tall = np.minimum(y1[:, None], y1[None, :]) - np.maximum(y0[:, None], y0[None, :])
    clash = (wide > TOLERANCE) & (tall > TOLERANCE)
    np.fill_diagonal(clash, False)
    return sorted(
        {(owners[i], owners[j]) for i, j in zip(*np.nonzero(clash), strict=True) if i < j}
    )


def blank_pages(pdf: bytes) -> list[int]:
    """Pages whose rendering is (nearly) all one colour."""
    document = pypdfium2.PdfDocument(pdf)
    blank = []
    for number in range(len(document)):
        pixels = document[number].render(scale=0.5, grayscale=True).to_numpy()
        if (pixels < 200).mean() < 0.002:  # fewer than 0.2 % of the pixels are ink
            blank.append(number + 1)
    return blank


def at(days_ago: int, hour: int) -> datetime.datetime:
    day = timezone.localdate() - datetime.timedelta(days=days_ago)
    return timezone.make_aware(datetime.datetime.combine(day, datetime.time(hour)))


@pytest.fixture
def history(world):
    """Three exercises over three weeks, three sessions on one day, goals and pain scores: enough
    sessions for the table to run over a page."""
    squat = make_exercise(world.clinic)
    arm = make_exercise(world.clinic, name="Shoulder abduction with a long name to wrap")
    lunge = make_exercise(world.clinic, name="Forward lunge")
    for day in range(20, 0, -1):
        for i, exercise in enumerate((squat, arm, lunge)):
            recording = session(world.patient, exercise, at(day, 8 + 3 * i), score=50 + day)
            Recording.objects.filter(pk=recording.pk).update(pain_score=day % 10)
    for hour in (13, 15, 19):  # three more squats on the last day
        session(world.patient, squat, at(1, hour))
    by = timezone.localdate() + datetime.timedelta(days=30)
    Goal.objects.create(patient=world.patient, exercise=squat, measure="score", target=85, by=by)
    Goal.objects.create(
        patient=world.patient, exercise=squat, measure="knee_flexion_left", target=95, by=by
    )
    return world


def test_progress_pdf_has_no_overlapping_text_and_no_blank_page(history):
    content = progress_content(history.patient, None, None)
    pdf = progress_pdf(content)
    pages = text_lines(pdf)
    assert len(pages) >= 3
    for number, lines in enumerate(pages, start=1):
        assert overlaps(lines) == [], f"page {number}"
    assert blank_pages(pdf) == []


def test_progress_pdf_axes_are_dates_with_units(history):
    content = progress_content(history.patient, None, None)
    texts = [text for page in text_lines(progress_pdf(content)) for text, _ in page]
    day = re.compile(r"^\d{1,2} (Jan|Feb|Mar|Apr|May|Jun|Jul|Aug|Sep|Oct|Nov|Dec)$")
    assert sum(bool(day.match(t)) for t in texts) >= 8  # tick labels name days
    assert not any("session (number" in t for t in texts)
    assert texts.count("date of the session") == 4  # the score chart and one per exercise
    assert "score (0–100)" in texts and texts.count("range of motion (°)") == 3


def test_progress_pdf_tables_never_leave_a_lone_row(history):
    content = progress_content(history.patient, None, None)
    pages = text_lines(progress_pdf(content))
    dated = re.compile(r"^\d{4}-\d{2}-\d{2}")
    per_page = [sum(bool(dated.match(t)) for t, _ in page) for page in pages]
    assert sum(per_page) == len(content["rows"])
    assert all(count == 0 or count >= 3 for count in per_page), per_page


def test_recording_pdf_has_no_overlapping_text(world):
    squat = make_exercise(world.clinic)
    recording = analysed(world.patient, squat, summary(80.0, squat_angles()))
    pdf = recording_pdf(recording_content(recording))
    for number, lines in enumerate(text_lines(pdf), start=1):
        assert overlaps(lines) == [], f"page {number}"
    assert blank_pages(pdf) == []


def test_the_overlap_check_finds_overlapping_text():
    """The check itself: two strings drawn on top of each other are caught."""
    a = ("chart title", [(10.0, 10.0, 16.0, 20.0), (16.0, 10.0, 22.0, 20.0)])
    b = ("axis title", [(20.0, 12.0, 26.0, 22.0)])
    c = ("far away", [(100.0, 100.0, 106.0, 110.0)])
    assert overlaps([a, b, c]) == [("chart title", "axis title")]
    assert overlaps([a, c]) == []
