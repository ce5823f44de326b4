"""The one history CSV: read back with pandas, units in every numeric column's name, the pain,
no rig joint names, an empty score and a note for a recording that does not show its exercise,
and the same file from the patient page's link and from the API."""

from __future__ import annotations

import datetime
import io
import re

import pandas as pd
import pytest
from django.urls import reverse
from django.utils import timezone
from rest_framework.test import APIClient

from analysis.pipeline.results import (
    AnalysisSummary,
    AngleRange,
    ExerciseMatch,
    RepetitionResult,
)
from tests.personas import make_exercise, make_recording
from webapp.recordings.models import AnalysisRun, Recording, RunStatus

UNIT = re.compile(r"\((count|/100|0-10|°)\)$")
RIG_JOINTS = ("LeftCollar", "Head", "RightUpLeg")
NOT_THE_EXERCISE = "This recording does not look like a deep squat: the knees hardly moved."


def summary(score: float | None, passed: tuple[bool, ...], fits: bool = True) -> dict:
    reps = tuple(
        RepetitionResult(start=10 * i, end=10 * i + 9, peak=10 * i + 5, score=score or 0, passed=p)
        for i, p in enumerate(passed)
    )
    result = AnalysisSummary(
        frames=60,
        fps=30.0,
        landmarks=(),
        repetitions=reps,
        score=score,
        # What the old exports wrote as rom_<joint> / gamma_<joint>: the rig's own names.
        range_of_motion={"LeftCollar": 12.0, "RightUpLeg": 80.0},
        gamma={"Head": 0.4},
        clinical_angles={"knee_flexion_left": AngleRange(4.0, 101.5)} if fits else {},
        match=ExerciseMatch() if fits else ExerciseMatch(False, NOT_THE_EXERCISE, None),
    )
    return result.to_json()


def analysed(
    patient, exercise, data: dict, days_ago: int, pain: int | None, *, effort: int | None = None
) -> Recording:
    recording = make_recording(patient, exercise)
    AnalysisRun.objects.filter(recording=recording).update(status=RunStatus.SUCCEEDED, summary=data)
    when = timezone.now() - datetime.timedelta(days=days_ago)
    Recording.objects.filter(pk=recording.pk).update(
        uploaded_at=when, pain_score=pain, effort=effort
    )
    return recording


@pytest.fixture
def history(world):
    squat = make_exercise(world.clinic)
    analysed(
        world.patient, squat, summary(72.25, (True, False, True)), days_ago=8, pain=6, effort=7
    )
    analysed(world.patient, squat, summary(None, (), fits=False), days_ago=5, pain=None)
    analysed(world.patient, squat, summary(88.0, (True, True)), days_ago=1, pain=2)
    return squat


def api_csv(world) -> bytes:
    client = APIClient()
    client.force_authenticate(world.therapist)
    response = client.get(reverse("api-patient-history-csv", kwargs={"pk": world.patient.pk}))
    assert response.status_code == 200
    return response.content


def page_csv(client, world):
    client.force_login(world.therapist)
    return client.get(reverse("patients:history-csv", kwargs={"pk": world.patient.pk}))


def test_every_numeric_column_names_its_unit(world, history):
    frame = pd.read_csv(io.BytesIO(api_csv(world)))
    numeric = [c for c in frame.columns if pd.api.types.is_numeric_dtype(frame[c])]
    assert "score (/100)" in numeric and "pain (0-10)" in numeric
    assert "left knee flexion range (°)" in numeric
    assert [c for c in numeric if not UNIT.search(c)] == []
    text_columns = set(frame.columns) - set(numeric)
    assert text_columns == {"date (UTC)", "exercise", "note"}


def test_the_history_holds_pain_scores_and_counts_oldest_first(world, history):
    frame = pd.read_csv(io.BytesIO(api_csv(world)))
    assert len(frame) == 3
    assert pd.to_datetime(frame["date (UTC)"]).is_monotonic_increasing
    assert frame["pain (0-10)"].tolist()[0::2] == [6, 2] and frame["pain (0-10)"].isna()[1]
    effort = frame["effort Borg CR10 (0-10)"]
    assert effort.tolist()[0] == 7 and effort.isna().tolist()[1:] == [True, True]
    assert frame["repetitions (count)"].tolist() == [3, 0, 2]
    assert frame["repetitions passed (count)"].tolist() == [2, 0, 2]
    assert frame["left knee flexion range (°)"].tolist()[0::2] == [97.5, 97.5]


def test_a_recording_that_does_not_fit_has_no_score_and_a_note(world, history):
    frame = pd.read_csv(io.BytesIO(api_csv(world)))
    assert frame["score (/100)"].isna().tolist() == [False, True, False]
    assert frame["score (/100)"].dropna().tolist() == [72.25, 88.0]
    assert frame["note"].iloc[1] == f"No score: {NOT_THE_EXERCISE}"
    assert frame["note"].iloc[[0, 2]].isna().all()


def test_no_rig_joint_or_internal_field_names(world, history):
    text = api_csv(world).decode()
    header = text.splitlines()[0]
    assert [name for name in RIG_JOINTS if name in text] == []
    assert "rom_" not in header and "gamma_" not in header and "_" not in header
    for internal in ("exercise_name", "pain_score", "passed,", "knee_flexion_left"):
        assert internal not in header


def test_page_link_and_api_give_the_same_file(client, world, history):
    from_page = page_csv(client, world)
    assert from_page.status_code == 200
    assert from_page["Content-Type"].startswith("text/csv")
    assert from_page.content == api_csv(world)
    assert from_page["Content-Disposition"].startswith("attachment; filename=")


def test_a_typed_name_is_not_run_as_a_spreadsheet_formula(client, world, history):
    type(history).objects.filter(pk=history.pk).update(name="=HYPERLINK(1)")
    frame = pd.read_csv(io.BytesIO(page_csv(client, world).content))
    assert frame["exercise"].tolist() == ["'=HYPERLINK(1)"] * 3
