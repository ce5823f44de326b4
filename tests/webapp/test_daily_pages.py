"""Issue 18 without a browser: the patient page lists every recording (paged, linked, scored), a
patient uploads only for themselves and only prescribed exercises, pain of 6/10 or more reaches
the attention list, the progress PDF keeps exercises apart, and the viewer's skeleton-shape rule
(run with node) skips a floor-level placement root."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest
from django.urls import reverse

from tests.webapp.test_dashboard_home import attention_text, exercise, prescribe, recording
from webapp.recordings.forms import UploadForm, upload_choices
from webapp.recordings.models import Recording
from webapp.reports.content import rom_series

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.django_db
def test_patient_page_links_every_recording_with_score_and_status_page_by_page(client, world):
    squat = exercise(world.clinic)
    made = [recording(world.patient, squat, days, score=50 + days) for days in range(1, 24)]
    client.force_login(world.therapist)
    url = reverse("patients:detail", args=[world.patient.pk])
    first = client.get(url).content.decode()
    second = client.get(url, {"recordings_page": 2}).content.decode()
    for rec in made:  # newest 20 on the first page, the 3 oldest on the second
        page = first if rec in made[:20] else second
        assert reverse("recordings:detail", args=[rec.pk]) in page
    oldest = made[-1]
    row = second[second.index(f'data-recording="{oldest.pk}"') :]
    row = row[: row.index("</tr>")]
    assert ">73<" in row and "Succeeded" in row  # its score (50 + 23 days) and status
    assert "recordings_page=2" in first and "Page 1 of 2" in first


@pytest.mark.django_db
def test_a_patient_uploads_for_themselves_among_their_prescribed_exercises(world):
    squat, reach = exercise(world.clinic), exercise(world.clinic, "Reach")
    for marked in (squat, reach):  # key poses marked: an exercise without them is not offered
        marked.tutor_landmark_frames, marked.tutor_landmark_types = [0, 40], [1, 2]
        marked.save()
    prescribe(world.patient, squat)
    prescribe(world.other_patient, reach)
    mine = upload_choices(world.patient_user)
    assert mine["own_patient"] == world.patient
    assert list(mine["exercises"]) == [squat]
    form = UploadForm(**mine)
    assert "patient" not in form.fields
    staff = upload_choices(world.therapist)
    assert "own_patient" not in staff and set(staff["exercises"]) == {squat, reach}
    assert "patient" in UploadForm(**staff).fields


@pytest.mark.django_db
def test_pain_of_six_or_more_reaches_the_attention_list(client, world):
    squat = exercise(world.clinic)
    client.force_login(world.therapist)
    calm = recording(world.patient, squat, 1, score=80)
    Recording.objects.filter(pk=calm.pk).update(pain_score=5)
    assert "Ann Example" not in attention_text(client)
    sore = recording(world.patient, squat, 0.5, score=80)
    Recording.objects.filter(pk=sore.pk).update(pain_score=6)
    section = attention_text(client)
    assert "Ann Example" in section and "pain reported" in section and "pain 6/10" in section
    assert reverse("recordings:detail", args=[sore.pk]) in section
    old = recording(world.other_patient, squat, 20, score=80)  # older than two weeks
    Recording.objects.filter(pk=old.pk).update(pain_score=9)
    assert "Bob Example" not in attention_text(client)


def test_progress_pdf_range_of_motion_lines_never_join_two_exercises():
    """Clinical angles' ranges (as in the recording's table), named with their normal range."""
    knee = "knee_flexion_left"
    points = [
        {"exercise_name": "Deep squat", "clinical_angles": {knee: {"range": 90.0}}},
        {"exercise_name": "Shoulder abduction", "clinical_angles": {knee: {"range": 5.0}}},
        {"exercise_name": "Deep squat", "clinical_angles": {knee: {"range": 95.0}}},
    ]
    days = ("2026-11-02T09:00", "2026-11-02T15:00", "2026-11-04T10:00")
    for point, when in zip(points, days, strict=True):
        point["date"] = when  # x: days since the report's first day, same-day sessions spread
    charts = rom_series(points)
    label = "Left knee flexion"
    assert charts == {
        "Deep squat": {label: [(round(1 / 3, 4), 90.0), (2.5, 95.0)]},
        "Shoulder abduction": {label: [(round(2 / 3, 4), 5.0)]},
    }


SHAPES = {
    # Bandai-Namco: joint_Root (floor, zero offset) → Hips → spine and both legs.
    "bandai": ([-1, 0, 1, 1, 3, 1, 5], {"bones": [1], "joints": [0]}),
    # UI-PRMD / CMU: the root is the pelvis, with the spine and both thighs below it.
    "pelvis_root": ([-1, 0, 1, 0, 3, 0, 5], {"bones": [], "joints": []}),
}


@pytest.mark.parametrize("shape", SHAPES)
def test_viewer_skips_a_placement_root_and_keeps_a_pelvis_root(shape):
    node = shutil.which("node")
    assert node, "node is needed (it serves the front-end build too)"
    parents, expected = SHAPES[shape]
    module = (ROOT / "webapp/static/js/skeleton_shape.js").as_uri()
    script = (
        f"import {{ hiddenParts }} from '{module}';"
        f"const h = hiddenParts({json.dumps(parents)});"
        "console.log(JSON.stringify({ bones: [...h.bones], joints: [...h.joints] }));"
    )
    out = subprocess.run(
        [node, "--input-type=module", "-e", script], capture_output=True, text=True, check=True
    )
    assert json.loads(out.stdout) == expected
