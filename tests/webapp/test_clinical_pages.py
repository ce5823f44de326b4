"""Clinical measures on the pages: the recording page's angle table (plain words, degrees, normal
ranges) and reachable workspace, the progress page's per-exercise angle series, the recording
PDF's angle table, and the patient page's history CSV link (session-authenticated)."""

from __future__ import annotations

import base64
import datetime
import json
import re
import zlib

import pytest
from django.urls import reverse
from django.utils import timezone

from analysis.clinical import ANGLE_NAMES
from analysis.pipeline.results import (
    AnalysisSummary,
    AngleRange,
    RepetitionResult,
    WorkspaceSummary,
)
from tests.personas import make_exercise, make_recording
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from webapp.reports.content import recording_content
from webapp.reports.pdf import recording_pdf

KNEE_LEFT = AngleRange(2.5, 95.0)
KNEE_RIGHT = AngleRange(4.0, 91.0)
TRUNK = AngleRange(-1.0, 28.25)
SHOULDER = AngleRange(5.0, 150.0)
HULL = WorkspaceSummary(
    side="right",
    relative_area=0.2537,
    quadrants={"upper_medial": 0.0, "upper_lateral": 0.1245, "lower_medial": 0.0,
               "lower_lateral": 0.1292},
    vertices=((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (0.7, 0.7, 0.1)),
    faces=((0, 1, 2), (0, 1, 3)),
)  # fmt: skip


def summary(score: float, angles: dict[str, AngleRange], workspace=None) -> dict:
    reps = tuple(
        RepetitionResult(
            start=10 * i, end=10 * i + 9, peak=10 * i + 5, score=score,
            clinical_angles={name: AngleRange(a.min + i, a.max - i) for name, a in angles.items()},
        )
        for i in range(3)
    )  # fmt: skip
    result = AnalysisSummary(
        frames=40, fps=30.0, landmarks=(), repetitions=reps, score=score,
        clinical_angles=angles, workspace=workspace or {},
    )  # fmt: skip
    return result.to_json()


def analysed(patient, exercise, data: dict, days_ago: int = 1) -> Recording:
    recording = make_recording(patient, exercise)
    AnalysisRun.objects.filter(recording=recording).update(status=RunStatus.SUCCEEDED, summary=data)
    when = timezone.now() - datetime.timedelta(days=days_ago)
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when)
    return Recording.objects.get(pk=recording.pk)


@pytest.fixture
def squat(world):
    exercise = make_exercise(world.clinic)
    exercise.involved_joints = ["KneeLeft", "KneeRight", "HipLeft", "HipRight"]
    exercise.save()
    return exercise


@pytest.fixture
def raise_arm(world):
    exercise = make_exercise(world.clinic, name="Shoulder abduction")
    exercise.involved_joints = ["ShoulderRight", "ElbowRight"]
    exercise.save()
    return exercise


def squat_angles() -> dict[str, AngleRange]:
    return {
        "knee_flexion_left": KNEE_LEFT,
        "knee_flexion_right": KNEE_RIGHT,
        "trunk_flexion": TRUNK,
    }


def page(client, user, url: str) -> str:
    client.force_login(user)
    response = client.get(url)
    assert response.status_code == 200
    return response.content.decode()


def section(html: str, element_id: str) -> str:
    start = html.index(f'id="{element_id}"')
    return html[start : html.index("</section>", start)]


def test_recording_page_shows_the_angle_table_in_plain_words_with_norms(client, world, squat):
    recording = analysed(world.patient, squat, summary(80.0, squat_angles()))
    html = page(client, world.therapist, reverse("recordings:detail", kwargs={"pk": recording.pk}))
    table = section(html, "clinical")
    assert "Left knee flexion" in table and "Right knee flexion" in table
    assert "Trunk flexion" in table
    assert "95°" in table and "92°" in table  # max and range (95.0 − 2.5 = 92.5, shown 92°)
    assert "0° to 135°" in table  # the normal adult knee range
    assert "-25° to 80°" in table  # trunk flexion's
    assert "used in this exercise" in table  # the knees, moved by a squat, come first
    assert table.index("Knees") < table.index("Trunk")
    assert "Range per repetition" in table
    assert not any(name in html for name in ANGLE_NAMES)  # never the internal names
    assert "Reachable workspace" not in html  # a squat has no workspace


def test_recording_page_without_clinical_angles_has_no_table(client, world, squat):
    data = summary(70.0, {})
    data.pop("clinical_angles")
    data.pop("workspace")  # a run stored before the clinical measures
    recording = analysed(world.patient, squat, data)
    html = page(client, world.therapist, reverse("recordings:detail", kwargs={"pk": recording.pk}))
    assert 'id="clinical"' not in html


def test_workspace_appears_for_an_arm_exercise(client, world, raise_arm):
    data = summary(75.0, {"shoulder_abduction_right": SHOULDER}, workspace={"right": HULL})
    recording = analysed(world.patient, raise_arm, data)
    html = page(client, world.therapist, reverse("recordings:detail", kwargs={"pk": recording.pk}))
    box = section(html, "clinical")
    assert "Right shoulder abduction" in box and "0° to 180°" in box
    assert "Reachable workspace" in box and "Right hand" in box
    assert "25.4&nbsp;%" in box  # of the front hemisphere
    assert 'id="workspace-canvas"' in box and "js/workspace_view.js" in box
    hulls = json.loads(re.search(r'id="workspace-data"[^>]*>(.*?)</script>', html, re.S)[1])
    assert hulls[0]["side"] == "right" and len(hulls[0]["faces"]) == 2
    # the import map the 3D view relies on comes before it
    assert html.index('type="importmap"') < html.index("js/workspace_view.js")


def test_progress_page_shows_angle_series_per_exercise(client, world, squat, raise_arm):
    analysed(world.patient, squat, summary(60.0, squat_angles()), days_ago=9)
    deeper = {**squat_angles(), "knee_flexion_left": AngleRange(1.0, 110.0)}
    analysed(world.patient, squat, summary(80.0, deeper), days_ago=2)
    arm = summary(75.0, {"shoulder_abduction_right": SHOULDER}, workspace={"right": HULL})
    analysed(world.patient, raise_arm, arm, days_ago=5)
    html = page(
        client, world.therapist, reverse("reports:progress", kwargs={"pk": world.patient.pk})
    )
    box = section(html, "clinical-progress")
    assert "Deep squat" in box and "Shoulder abduction" in box
    assert "Left knee flexion" in box and "Reachable area, % of the front hemisphere" in box
    assert "js/clinical_progress.js" in html
    data = json.loads(re.search(r'id="clinical-progress-data"[^>]*>(.*?)</script>', html, re.S)[1])
    by_name = {ex["exercise"]: ex for ex in data}
    squat_series = by_name["Deep squat"]
    assert len(squat_series["dates"]) == 2  # the arm session is not joined into the squat's line
    knee = next(a for a in squat_series["angles"] if a["label"] == "Left knee flexion")
    assert knee["range"] == [92.5, 109.0]
    assert squat_series["workspace"] == []
    arm_series = by_name["Shoulder abduction"]
    assert arm_series["dates"] == [arm_series["dates"][0]]
    assert arm_series["workspace"] == [{"side": "right", "label": "Right hand", "percent": [25.4]}]
    assert not any(name in box for name in ANGLE_NAMES)
    # the progress JSON carries the ranges too (read through AngleRange)
    points = client.get(reverse("patients:progress", kwargs={"pk": world.patient.pk})).json()
    last = points["points"][-1]["clinical_angles"]["knee_flexion_left"]
    assert last == {"min": 1.0, "max": 110.0, "range": 109.0}


def pdf_text(pdf: bytes) -> str:
    """The page text of a reportlab PDF (ASCII85 + Flate content streams)."""
    text = []
    for raw in re.findall(rb"stream\r?\n(.*?)endstream", pdf, re.S):
        data = raw.strip().removesuffix(b"~>")
        try:
            text.append(zlib.decompress(base64.a85decode(data)).decode("latin-1"))
        except (ValueError, zlib.error):
            continue
    return "".join(text)


def test_recording_pdf_has_the_angle_table_with_norms(world, squat):
    recording = analysed(world.patient, squat, summary(80.0, squat_angles()))
    content = recording_content(recording)
    assert ["Knees: Left knee flexion", "2°", "95°", "92°", "0° to 135°"] in content[
        "clinical_angles"
    ]
    text = pdf_text(recording_pdf(content))
    assert "Joint angles \\(degrees\\)" in text
    assert "Knees: Left knee flexion" in text and "Trunk: Trunk flexion" in text
    assert "Normal adult range" in text
    assert "knee_flexion_left" not in text


def test_recording_pdf_has_the_workspace_for_an_arm_exercise(world, raise_arm):
    data = summary(75.0, {"shoulder_abduction_right": SHOULDER}, workspace={"right": HULL})
    content = recording_content(analysed(world.patient, raise_arm, data))
    assert content["clinical_workspace"][0][:2] == ["Right hand", "25.4 %"]
    assert "Reachable workspace" in pdf_text(recording_pdf(content))


def test_patient_page_links_the_history_csv_the_browser_can_fetch(client, world, squat):
    analysed(world.patient, squat, summary(80.0, squat_angles()))
    html = page(
        client, world.therapist, reverse("patients:detail", kwargs={"pk": world.patient.pk})
    )
    url = reverse("api-patient-history-csv", kwargs={"pk": world.patient.pk})
    assert f'href="{url}"' in html and "Download history (CSV)" in html
    browser_accept = "text/html,application/xhtml+xml,application/xml;q=0.9,*/*;q=0.8"
    response = client.get(url, HTTP_ACCEPT=browser_accept)  # the signed-in session, no token
    assert response.status_code == 200
    assert response["Content-Type"].startswith("text/csv")
    body = response.content.decode()
    assert "left knee flexion range (°)" in body.splitlines()[0] and "92.5" in body
    client.logout()
    assert client.get(url, HTTP_ACCEPT=browser_accept).status_code in (401, 403)


def test_the_api_recording_result_carries_clinical_angles_and_workspace(client, world, raise_arm):
    data = summary(75.0, {"shoulder_abduction_right": SHOULDER}, workspace={"right": HULL})
    recording = analysed(world.patient, raise_arm, data)
    client.force_login(world.therapist)
    body = client.get(reverse("api-recording", kwargs={"pk": recording.pk})).json()
    assert body["result"]["clinical_angles"]["shoulder_abduction_right"]["range"] == 145.0
    assert body["result"]["workspace"]["right"]["relative_area"] == 0.2537


def test_printable_report_has_the_angle_table(client, world, squat):
    recording = analysed(world.patient, squat, summary(80.0, squat_angles()))
    url = reverse("reports:recording-print", kwargs={"pk": recording.pk})
    html = page(client, world.therapist, url)
    assert "Joint angles (degrees)" in html and "Knees: Left knee flexion" in html
    assert "0° to 135°" in html and "knee_flexion_left" not in html
