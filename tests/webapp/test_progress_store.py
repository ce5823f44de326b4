"""The stored progress points: the progress endpoints answer what they answered when they read
every run's summary, read one row per run instead (never a summary), and a run that succeeds
stores its point on write."""

from __future__ import annotations

import datetime
import json
import random

import pytest
from django.db import connection
from django.test.utils import CaptureQueriesContext
from django.utils import timezone

from tests.personas import make_exercise, make_recording
from tests.webapp.test_clinical_pages import HULL, KNEE_LEFT, TRUNK, summary
from webapp.api.numbers import rounded, utc_iso
from webapp.dashboard.models import ProgressPoint
from webapp.demo import large_clinic
from webapp.patients.progress import clinical_progress, patient_progress
from webapp.patients.progress_store import (
    POINT_VALUES,
    angle_ranges_of,
    store_missing,
    summary_values,
    typed_field,
)
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from webapp.recordings.words import body_part
from workers import runs


def previous_progress(patient, exercise_id=None, since=None, until=None) -> list[dict]:
    """The computation before the store: every succeeded run's summary read by the database."""
    found = AnalysisRun.objects.filter(
        recording__patient=patient, status=RunStatus.SUCCEEDED
    ).order_by("recording__uploaded_at", "created_at")
    if exercise_id:
        found = found.filter(recording__exercise_id=exercise_id)
    if since:
        found = found.filter(recording__uploaded_at__date__gte=since)
    if until:
        found = found.filter(recording__uploaded_at__date__lte=until)
    fields = ("pk", "score", "recording_id", "recording__exercise_id")
    fields += ("recording__exercise__name", "recording__uploaded_at", "recording__pain_score")
    latest = {row["recording_id"]: row for row in found.values(*fields, **POINT_VALUES)}
    return [
        {
            "run": str(row["pk"]),
            "recording": str(row["recording_id"]),
            "exercise": str(row["recording__exercise_id"])
            if row["recording__exercise_id"]
            else None,
            "exercise_name": row["recording__exercise__name"]
            if row["recording__exercise_id"]
            else None,
            "date": row["recording__uploaded_at"].isoformat(),
            "score": row["score"],
            "repetitions": row["repetition_count"] or 0,
            "range_of_motion": row["range_of_motion"] or {},
            "gamma": row["gamma"] or {},
            "pain_score": row["recording__pain_score"],
            "clinical_angles": angle_ranges_of(row["clinical_angles"]),
            "workspace": {
                side: float(row[f"workspace_{side}"])
                for side in ("left", "right")
                if row[f"workspace_{side}"] is not None
            },
        }
        for row in latest.values()
    ]


def previous_api_body(patient, **filters) -> dict:
    points = previous_progress(patient, **filters)
    return {
        "patient": str(patient.pk),
        "points": [{**rounded(p), "date": utc_iso(p["date"])} for p in points],
    }


def previous_page_body(patient, **filters) -> dict:
    points = previous_progress(patient, **filters)
    joints = {j for p in points for field in ("range_of_motion", "gamma") for j in p[field]}
    labels = {joint: body_part(joint) for joint in sorted(joints)}
    return {"patient": str(patient.pk), "points": points, "labels": labels}


def analysed(patient, exercise, data: dict, days_ago: float, pain: int | None = None):
    recording = make_recording(patient, exercise)
    AnalysisRun.objects.filter(recording=recording).update(status=RunStatus.SUCCEEDED, summary=data)
    when = timezone.now() - datetime.timedelta(days=days_ago)
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when, pain_score=pain)
    return recording


def generated_summary(rng: random.Random, score: float | None) -> dict:
    """A summary as the scale generator writes it: range of motion and γ per body part."""
    return {"score": score, **large_clinic.summary_without_score(rng)}


@pytest.fixture
def history(world):
    """Two exercises; clinical and plain summaries; a re-analysed recording (two succeeded
    runs, the newer counts), a failed one, one without a score, one from another day."""
    rng = random.Random(4)
    squat = make_exercise(world.clinic)
    arm = make_exercise(world.clinic, name="Shoulder abduction")
    clinical = summary(72.456, {"knee_flexion_left": KNEE_LEFT, "trunk_flexion": TRUNK})
    analysed(world.patient, squat, clinical, 30, pain=3)
    analysed(world.patient, squat, summary(66.0, {}, workspace={"right": HULL}), 20)
    again = analysed(world.patient, arm, generated_summary(rng, 51.23456), 12, pain=0)
    AnalysisRun.objects.create(
        recording=again, status=RunStatus.SUCCEEDED, summary=generated_summary(rng, 58.98765)
    )
    failed = make_recording(world.patient, arm)
    AnalysisRun.objects.filter(recording=failed).update(status=RunStatus.FAILED)
    analysed(world.patient, arm, generated_summary(rng, None), 5)
    analysed(world.patient, squat, generated_summary(rng, 80.04), 1, pain=7)
    return {"squat": squat, "arm": arm}


FILTERS = (
    {},
    {"exercise": "squat"},
    {"since": 15},
    {"until": 10},
    {"exercise": "arm", "since": 14, "until": 2},
)


def resolved(filters: dict, history: dict) -> tuple[dict, dict]:
    """(keyword arguments, query string parameters) for one set of filters."""
    kwargs, params = {}, {}
    if "exercise" in filters:
        kwargs["exercise_id"] = params["exercise"] = str(history[filters["exercise"]].pk)
    today = timezone.now().date()
    for name in ("since", "until"):
        if name in filters:
            day = today - datetime.timedelta(days=filters[name])
            kwargs[name], params[name] = day, day.isoformat()
    return kwargs, params


def test_every_progress_answer_equals_the_computation_from_summaries(client, world, history):
    client.force_login(world.therapist)
    assert ProgressPoint.objects.count() == 0  # runs marked succeeded directly: read, then stored
    for reading in ("storing on the way", "stored"):
        for filters in FILTERS:
            kwargs, params = resolved(filters, history)
            assert patient_progress(world.patient, **kwargs) == previous_progress(
                world.patient, **kwargs
            ), (reading, filters)
            page = client.get(f"/patients/{world.patient.pk}/progress.json", params)
            assert page.status_code == 200 and page["Content-Type"] == "application/json"
            assert page.json() == previous_page_body(world.patient, **kwargs), (reading, filters)
            api = client.get(f"/api/v1/patients/{world.patient.pk}/progress/", params)
            assert api.status_code == 200 and api["Content-Type"] == "application/json"
            assert api.json() == previous_api_body(world.patient, **kwargs), (reading, filters)
        # One per recording's newest succeeded run (the superseded run and the failed one none).
        assert ProgressPoint.objects.count() == 5
    points = patient_progress(world.patient)
    assert len(points) == 5 and [p["score"] for p in points][2:4] == [58.98765, None]
    assert api.json()["points"][0]["score"] == 59.0  # rounded as the API rounds every score


def test_the_browsable_api_shows_the_same_points(client, world, history):
    client.force_login(world.therapist)
    url = f"/api/v1/patients/{world.patient.pk}/progress/"
    page = client.get(url, HTTP_ACCEPT="text/html")
    assert page.status_code == 200 and page["Content-Type"].startswith("text/html")
    assert str(history["squat"].pk) in page.content.decode()


def test_clinical_series_are_unchanged(world, history):
    series = clinical_progress(world.patient)
    assert [s["exercise"] for s in series] == ["Deep squat"]
    assert series[0]["dates"] == [p["date"][:10] for p in previous_progress(world.patient)[:2]]
    knee = next(a for a in series[0]["angles"] if a["name"] == "knee_flexion_left")
    assert knee["range"] == [KNEE_LEFT.range, None]
    assert series[0]["workspace"][0]["percent"] == [None, round(100 * HULL.relative_area, 1)]


def test_a_run_that_succeeds_stores_its_point_and_a_failed_one_none(world, history):
    patient_progress(world.patient)  # every run so far stored
    made = make_recording(world.patient, history["squat"])
    run = made.runs.get()
    token = runs.claim(str(run.pk), "test-worker")
    assert runs.succeed(str(run.pk), token, summary={"score": 91.5, "repetitions": [{}, {}]})
    point = ProgressPoint.objects.get(run=run)
    assert json.loads(point.page)["score"] == 91.5 and json.loads(point.page)["repetitions"] == 2
    broken = make_recording(world.patient, history["squat"]).runs.get()
    token = runs.claim(str(broken.pk), "test-worker")
    assert runs.fail(str(broken.pk), token, "The recording is too short.", "trace")
    assert not ProgressPoint.objects.filter(run=broken).exists()
    with CaptureQueriesContext(connection) as queries:
        points = patient_progress(world.patient)
    assert len(queries) == 1  # the new run's point was stored on write, not on this read
    assert points[-1]["run"] == str(run.pk) and points[-1]["score"] == 91.5


def test_stored_points_are_read_in_one_query_that_never_reads_a_summary(world, history):
    patient_progress(world.patient)
    with CaptureQueriesContext(connection) as queries:
        patient_progress(world.patient, exercise_id=str(history["arm"].pk))
    assert len(queries) == 1 and "summary" not in queries[0]["sql"]


def test_a_point_shows_the_recordings_current_exercise_name_and_pain_score(world, history):
    newest = patient_progress(world.patient)[-1]["recording"]
    history["squat"].name = "Deep squat, heels raised"
    history["squat"].save()
    Recording.objects.filter(pk=newest).update(pain_score=2)
    points = patient_progress(world.patient)
    assert points[0]["exercise_name"] == "Deep squat, heels raised"
    assert points[-1]["pain_score"] == 2
    assert points == previous_progress(world.patient)


def test_store_missing_stores_every_succeeded_run_once_and_reports(world, history):
    reports = []
    done = store_missing(AnalysisRun.objects.all(), batch=4, report=lambda n, s: reports.append(n))
    assert done == 6 and reports == [4, 6]
    assert store_missing(AnalysisRun.objects.all()) == 0
    assert ProgressPoint.objects.count() == 6


def test_the_database_and_python_read_the_same_values_from_a_summary(world, history):
    """`summary_values` (a bulk load's summaries, in Python) and `POINT_VALUES` (the database)
    take the same figures from every stored summary, missing keys included."""
    runs_ = AnalysisRun.objects.filter(recording__patient=world.patient).order_by()
    rows = {row["pk"]: row for row in runs_.values("pk", **POINT_VALUES)}
    checked = 0
    for run in runs_:
        expected = {name: rows[run.pk][name] for name in POINT_VALUES}
        assert summary_values(run.summary or {}) == expected
        checked += 1
    assert checked >= 5
    assert summary_values({}) == dict.fromkeys(POINT_VALUES)


def test_a_point_path_must_name_a_field_of_the_typed_summary():
    from analysis.pipeline.results import AnalysisSummary

    assert typed_field(AnalysisSummary, "range_of_motion") == "range_of_motion"
    with pytest.raises(LookupError, match="no field 'range_of_movement'"):
        typed_field(AnalysisSummary, "range_of_movement")
