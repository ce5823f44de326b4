"""History and progression: the progress JSON (page and API), the CSV export and pagination."""

from __future__ import annotations

import csv
import datetime
import io

import pytest
from django.urls import reverse
from django.utils import timezone
from rest_framework.test import APIClient

from tests.personas import make_exercise, make_recording
from webapp.recordings.models import Recording
from workers.analysis_task import analyse_run


def analysed(patient, exercise, source: str, days_ago: int):
    recording = make_recording(patient, exercise, source=source)
    assert analyse_run(str(recording.runs.get().pk)) == "succeeded"
    when = timezone.now() - datetime.timedelta(days=days_ago)
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when)
    return recording


@pytest.fixture
def history(world):
    squat = make_exercise(world.clinic)
    raise_arm = make_exercise(
        world.clinic, name="Shoulder abduction", source="reps/m07_s01_e01.bvh.gz"
    )
    old = analysed(world.patient, squat, "reps/m01_s01_e02.bvh.gz", days_ago=10)
    new = analysed(world.patient, squat, "reps/m01_s01_e03.bvh.gz", days_ago=1)
    arm = analysed(world.patient, raise_arm, "reps/m07_s01_e02.bvh.gz", days_ago=5)
    return squat, old, new, arm


def test_progress_json_lists_every_analysed_recording_oldest_first(client, world, history):
    squat, old, new, arm = history
    client.force_login(world.patient_user)
    url = reverse("patients:progress", kwargs={"pk": world.patient.pk})
    points = client.get(url).json()["points"]
    assert [p["recording"] for p in points] == [str(old.pk), str(arm.pk), str(new.pk)]
    first = points[0]
    assert 0 <= first["score"] <= 100 and first["repetitions"] >= 1
    assert first["range_of_motion"] and first["gamma"]
    only_squat = client.get(url, {"exercise": str(squat.pk)}).json()["points"]
    assert [p["recording"] for p in only_squat] == [str(old.pk), str(new.pk)]
    since = (timezone.localdate() - datetime.timedelta(days=3)).isoformat()
    recent = client.get(url, {"since": since}).json()["points"]
    assert [p["recording"] for p in recent] == [str(new.pk)]
    assert client.get(url, {"until": "yesterday"}).status_code == 400


def test_rerun_counts_once_by_its_newest_run(client, world, history):
    _, old, _, _ = history
    from webapp.recordings.models import AnalysisRun

    again = AnalysisRun.objects.create(recording=old)
    analyse_run(str(again.pk))
    client.force_login(world.therapist)
    points = client.get(reverse("patients:progress", kwargs={"pk": world.patient.pk})).json()
    assert [p["run"] for p in points["points"] if p["recording"] == str(old.pk)] == [str(again.pk)]


def test_csv_export_has_a_row_per_recording_in_plain_words(client, world, history):
    client.force_login(world.therapist)
    progress = client.get(reverse("patients:progress", kwargs={"pk": world.patient.pk})).json()
    rig_joints = {j for p in progress["points"] for j in (*p["range_of_motion"], *p["gamma"])}
    assert rig_joints  # the analyses measured the rig's joints: none of them may name a column
    response = client.get(reverse("patients:history-csv", kwargs={"pk": world.patient.pk}))
    assert response["Content-Type"].startswith("text/csv")
    assert "attachment" in response["Content-Disposition"]
    text = response.content.decode()
    rows = list(csv.reader(io.StringIO(text)))
    header, body = rows[0], rows[1:]
    assert header[:3] == ["date (UTC)", "exercise", "score (/100)"]
    assert not [c for c in header if c.startswith(("rom_", "gamma_")) or "_" in c]
    assert not [j for j in rig_joints if j in text]
    assert len(body) == 3 and {r[1] for r in body} == {"Deep squat", "Shoulder abduction"}
    assert all(0 <= float(r[2]) <= 100 for r in body)  # every recording shows its exercise


def test_api_pagination_and_date_filter(world, history):
    api = APIClient()
    api.force_authenticate(world.therapist)
    page = api.get(f"/api/v1/patients/{world.patient.pk}/recordings/", {"limit": 2}).json()
    assert page["count"] == 3 and len(page["results"]) == 2 and page["next"]
    rest = api.get(page["next"]).json()
    assert len(rest["results"]) == 1
    since = (timezone.localdate() - datetime.timedelta(days=3)).isoformat()
    progress = api.get(f"/api/v1/patients/{world.patient.pk}/progress/", {"since": since}).json()
    assert len(progress["points"]) == 1
