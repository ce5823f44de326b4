"""Issue 26 on the pages: an angle the recording could not measure shows as "not measurable in
this recording" with its reason (never as a figure), values outside the normal adult range are
flagged, and left and right ranges stand side by side with their difference, on the recording
page, the printable report and the PDF."""

from __future__ import annotations

import pytest
from django.urls import reverse

from analysis.clinical import ANGLE_NAMES
from analysis.pipeline.results import AnalysisSummary, AngleRange
from tests.personas import make_exercise
from tests.webapp.test_clinical_pages import analysed, page, pdf_text, section
from webapp.reports.content import recording_content
from webapp.reports.pdf import recording_pdf

ANKLE_NOTE = (
    "not measurable in this recording: 16 % of the frames read beyond what a body can reach "
    "(−60° to 45°), up to −89°; the capture lost track of this joint"
)
ANGLES = {
    "knee_flexion_left": AngleRange(2.0, 150.0),  # 15° above the normal 135°
    "knee_flexion_right": AngleRange(4.0, 120.0),
    "hip_flexion_left": AngleRange(-5.0, 100.0),
    "ankle_dorsiflexion_left": AngleRange(-10.0, 15.0),
}
NOTES = {"ankle_dorsiflexion_right": ANKLE_NOTE}


@pytest.fixture
def squat(world):
    exercise = make_exercise(world.clinic)
    exercise.involved_joints = ["KneeLeft", "KneeRight", "HipLeft", "HipRight"]
    exercise.save()
    return exercise


def stored(angles=ANGLES, notes=NOTES) -> dict:
    return AnalysisSummary(
        frames=40, fps=30.0, landmarks=(), repetitions=(), score=80.0,
        clinical_angles=angles, clinical_notes=notes,
    ).to_json()  # fmt: skip


def test_the_summary_keeps_its_clinical_notes():
    data = stored()
    assert data["clinical_notes"] == NOTES
    assert AnalysisSummary.from_json(data).clinical_notes == NOTES
    older = {k: v for k, v in data.items() if k != "clinical_notes"}
    assert AnalysisSummary.from_json(older).clinical_notes == {}


def test_recording_page_says_what_is_not_measurable_and_flags_and_compares_sides(
    client, world, squat
):
    recording = analysed(world.patient, squat, stored())
    html = page(client, world.therapist, reverse("recordings:detail", kwargs={"pk": recording.pk}))
    box = section(html, "clinical")
    row = box[box.index("Right ankle dorsiflexion") :].split("</tr>", 1)[0]
    assert "Not measurable in this recording" in row and "lost track of this joint" in row
    assert "°</td>" not in row.split("Not measurable")[0]  # no figure before the reason
    knee = box[box.index("Left knee flexion") :].split("</tr>", 1)[0]
    assert "15° above the normal range" in knee
    right_knee = box[box.index("Right knee flexion") :].split("</tr>", 1)[0]
    assert "normal range" not in right_knee.split("</td>", 4)[-1].replace("0° to 135°", "")
    symmetry = box[box.index('id="clinical-symmetry"') :]
    sides = symmetry[symmetry.index("Knee flexion") :].split("</tr>", 1)[0]
    assert "148°" in sides and "116°" in sides and "32°" in sides  # left 148, right 116
    assert "Hip flexion" not in symmetry.split("</table>")[0]  # one side only: no comparison
    assert not any(name in html for name in ANGLE_NAMES)


def test_printable_report_and_pdf_carry_the_notes_the_flags_and_the_sides(client, world, squat):
    recording = analysed(world.patient, squat, stored())
    content = recording_content(recording)
    rows = {row[0]: row for row in content["clinical_angles"]}
    assert rows["Knees: Left knee flexion"][4] == "0° to 135°: 15° above the normal range"
    assert rows["Ankles: Right ankle dorsiflexion"][1:] == [ANKLE_NOTE, "", "", ""]
    assert ["Knee flexion", "148°", "116°", "32°"] in content["clinical_symmetry"]
    html = page(
        client, world.therapist, reverse("reports:recording-print", kwargs={"pk": recording.pk})
    )
    assert "Not measurable in this recording" in html and "Left and right" in html
    text = pdf_text(recording_pdf(content))
    assert "not measurable in this recording" in text and "Left and right" in text
    assert "15\\260 above the normal range" in text or "15° above the normal range" in text
