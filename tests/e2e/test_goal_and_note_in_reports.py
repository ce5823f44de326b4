"""A therapist's goal and note, typed into the pages, reach the charts and the PDFs in a real
browser: the goal set on the patient page is drawn on the progress chart and listed in the
progress PDF; the note written on the recording page is printed in the recording's PDF."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from pypdf import PdfReader

from analysis.pipeline.results import AngleRange
from tests.e2e.test_clinical_angles_pages import sign_in
from tests.personas import make_exercise, make_world
from tests.webapp.test_clinical_pages import analysed, summary

pytestmark = pytest.mark.e2e
NOTE = "Knees drift inward at the bottom; cue them over the toes next session."


@pytest.fixture
def patient_with_history(transactional_db, eager_celery):
    world = make_world()
    squat = make_exercise(world.clinic)
    recordings = [
        analysed(world.patient, squat, summary(score, {"knee_flexion_left": AngleRange(0.0, knee)}),
                 days_ago=days_ago)
        for days_ago, knee, score in ((9, 70.0, 60.0), (2, 80.0, 72.0))
    ]  # fmt: skip
    return world, recordings[-1]


def pdf_text(page, link: str) -> str:
    with page.expect_download() as download:
        page.click(link)
    content = Path(download.value.path()).read_bytes()
    return " ".join(p.extract_text() for p in PdfReader(io.BytesIO(content)).pages)


def test_a_goal_set_on_the_page_is_on_the_chart_and_in_the_pdf(
    page, live_server, patient_with_history
):
    world, _ = patient_with_history
    sign_in(page, live_server.url)
    page.goto(f"{live_server.url}/patients/{world.patient.pk}/")
    page.eval_on_selector("#goals details", "d => { d.open = true; }")
    page.select_option("#id_measure", value="score")
    page.fill("#id_target", "85")
    page.fill("#id_by", "2027-03-12")
    page.click("#add-goal button")
    page.wait_for_selector("#goals .goal")
    assert "85" in page.inner_text("#goals .goal-words")
    page.goto(f"{live_server.url}/patients/{world.patient.pk}/progress/")
    page.wait_for_selector(".js-plotly-plot .scatterlayer")
    dashed = page.locator(".scatterlayer path.js-line[style*='stroke-dasharray']")
    assert dashed.count() >= 1  # the goal's line on the score chart
    text = pdf_text(page, "#progress-pdf")
    assert "Goals" in text and "85" in text and "12 March 2027" in text


def test_a_note_written_on_the_recording_page_is_in_its_pdf(
    page, live_server, patient_with_history
):
    _, recording = patient_with_history
    sign_in(page, live_server.url)
    page.goto(f"{live_server.url}/recordings/{recording.pk}/")
    page.fill("#add-note textarea", NOTE)
    page.click("#add-note button")
    page.wait_for_selector(".clinical-note")
    assert NOTE in page.inner_text("#clinical-notes")
    text = " ".join(pdf_text(page, "#report-pdf").split())
    assert "Clinical notes" in text and NOTE in text
