"""Issue 34 item 5: the charts and reports show clinical angles (named, with their normal range
and unit), the same numbers as the table of angles beside them; body segments' angles only where
a therapist asks for them, under their own name."""

from __future__ import annotations

import io

import pytest
from django.urls import reverse
from pypdf import PdfReader

from analysis.clinical.labels import angle_label
from tests.personas import make_exercise, make_recording
from webapp.patients.progress import progress_charts
from webapp.reports.content import progress_content
from webapp.reports.pdf import progress_pdf
from workers.analysis_task import analyse_run

SEGMENT_WORDS = ("head", "collarbone", "foot", "upper arm", "lower leg", "toe")


@pytest.fixture
def sessions(world):
    """A squat and a shoulder abduction, each analysed by the real pipeline."""
    squat = make_exercise(world.clinic, "Deep squat", "reps/m01_s01_e01.bvh.gz")
    arms = make_exercise(world.clinic, "Shoulder abduction", "reps/m07_s01_e01.bvh.gz")
    done = {}
    for name, exercise, source in (
        ("squat", squat, "reps/m01_s01_e02.bvh.gz"),
        ("arms", arms, "reps/m07_s01_e02.bvh.gz"),
    ):
        recording = make_recording(world.patient, exercise, source=source)
        assert analyse_run(str(recording.runs.get().pk)) == "succeeded"
        done[name] = recording
    return done


def playback(client, recording) -> dict:
    return client.get(reverse("reports:playback", kwargs={"pk": recording.pk})).json()


def test_the_chart_curves_are_the_tables_angles(client, world, sessions):
    client.force_login(world.therapist)
    for recording in sessions.values():
        table = recording.runs.get().result.clinical_angles
        data = playback(client, recording)
        curves = {s["angle"]: s for s in data["angles"]["series"]}
        assert curves and set(curves) == set(table)
        for name, curve in curves.items():
            values = [v for v in curve["values"] if v is not None]
            assert min(values) == pytest.approx(table[name].min, abs=0.01), name
            assert max(values) == pytest.approx(table[name].max, abs=0.01), name
            assert not any(word in curve["label"].lower() for word in SEGMENT_WORDS)
        shown = {s["label"] for s in data["angles"]["series"] if s["involved"]}
        assert all(s["normal"] for s in data["angles"]["series"] if s["involved"])
        if recording == sessions["squat"]:
            assert {"Left knee flexion", "Right knee flexion"} <= shown
        else:
            assert "Left shoulder abduction" in shown or "Right shoulder abduction" in shown
        # body segments stay available, under their own name
        assert data["segments"]["series"] and "angle" not in data["segments"]["series"][0]


def test_only_a_therapist_is_offered_the_segments(client, world, sessions):
    url = reverse("recordings:detail", kwargs={"pk": sessions["squat"].pk})
    client.force_login(world.therapist)
    page = client.get(url).content.decode()
    assert "Joint angles (degrees, over time in seconds)" in page
    assert "angles between body segments (not clinical angles" in page
    client.force_login(world.patient_user)
    assert "angles between body segments" not in client.get(url).content.decode()


def test_progress_page_and_pdf_show_the_angles_of_the_table(world, sessions):
    charts = {c["exercise"]: c for c in progress_charts(world.patient)}
    squat = [line["label"] for line in charts["Deep squat"]["rom"]]
    assert any(label.startswith("Left knee flexion (normal") for label in squat), squat
    assert not any(word in label.lower() for label in squat for word in SEGMENT_WORDS)
    table = sessions["arms"].runs.get().result.clinical_angles
    ranges = {angle_label(name): span.range for name, span in table.items()}
    lines = charts["Shoulder abduction"]["rom"]
    assert lines and any("shoulder abduction" in line["label"] for line in lines)
    for line in lines:  # each line is one of the table's angles, with the table's range
        assert line["y"][0] == pytest.approx(ranges[line["label"].split(" (normal")[0]], abs=0.01)
    content = progress_content(world.patient, None, None)
    text = " ".join(
        page.extract_text() for page in PdfReader(io.BytesIO(progress_pdf(content))).pages
    )
    assert "range of the joint angles moved most" in text
    assert "shoulder abduction (normal 0° to 180°)" in " ".join(text.split())
    assert "knee flexion (normal 0° to 135°)" in " ".join(text.split())
    assert not any(
        f"{side} {word}" in text.lower() for side in ("left", "right") for word in SEGMENT_WORDS
    )
