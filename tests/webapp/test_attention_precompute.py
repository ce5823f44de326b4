"""The stored attention list: the home page reads a page of small rows (a fixed, small number of
queries), and a run that succeeds or fails updates its patient's row on write, without waiting
for the beat refresh."""

from __future__ import annotations

import datetime

from django.db import connection
from django.test.utils import CaptureQueriesContext
from django.urls import reverse
from django.utils import timezone

from tests.webapp.test_dashboard_home import attention_text, exercise, fill_clinic, recording
from webapp.dashboard.models import PatientAttention
from webapp.dashboard.precompute import read_page, refresh_all
from webapp.recordings.models import AnalysisRun, RunStatus
from workers import runs


def finish(run: AnalysisRun, outcome: str, score: float | None = None) -> None:
    """End a run as a worker does: claim it, then succeed or fail it."""
    AnalysisRun.objects.filter(pk=run.pk).update(status=RunStatus.QUEUED)
    token = runs.claim(str(run.pk), "test-worker")
    assert token
    if outcome == "failed":
        assert runs.fail(str(run.pk), token, "The recording is too short.", "trace")
    else:
        assert runs.succeed(str(run.pk), token, summary={"score": score}, score=score)


def test_reading_a_page_takes_two_queries_for_any_clinic_size(world):
    fill_clinic(world, 60, recordings_each=4)
    refresh_all()
    assert PatientAttention.objects.filter(clinic=world.clinic).count() >= 20
    with CaptureQueriesContext(connection) as queries:
        page = read_page(world.clinic.pk, 2, 10)
        names = [row.patient.display_name for row in page.object_list]
        reasons = [r["text"] for row in page.object_list for r in row.reasons]
        total = page.paginator.count
    assert len(queries) == 2, [q["sql"] for q in queries]
    assert len(names) == 10 and reasons and total >= 20


def test_a_failed_run_puts_the_patient_on_the_list_at_once(client, world):
    squat = exercise(world.clinic)
    made = recording(world.patient, squat, 0, RunStatus.RUNNING)
    client.force_login(world.therapist)
    assert "Ann Example" not in attention_text(client, refresh=False)
    finish(made.runs.get(), "failed")
    section = attention_text(client, refresh=False)  # no beat refresh in between
    assert "Ann Example" in section and "failed analysis" in section
    assert reverse("recordings:detail", args=[made.pk]) in section


def test_a_succeeding_rerun_takes_the_failure_off_and_a_falling_score_on(client, world):
    squat = exercise(world.clinic)
    for days_ago, score in ((20, 80), (15, 84), (10, 82)):
        recording(world.patient, squat, days_ago, score=score)
    latest = recording(world.patient, squat, 1, RunStatus.FAILED)
    refresh_all()
    client.force_login(world.therapist)
    assert "failed analysis" in attention_text(client, refresh=False)
    rerun = AnalysisRun.objects.create(recording=latest)
    finish(rerun, "succeeded", score=60.0)
    section = attention_text(client, refresh=False)
    assert "failed analysis" not in section
    assert "reason-falling" in section and "score 60, down 22 from 82" in section
    second = AnalysisRun.objects.create(recording=latest)
    finish(second, "succeeded", score=83.0)
    assert "Ann Example" not in attention_text(client, refresh=False)
    assert not PatientAttention.objects.filter(patient=world.patient).exists()


def test_beat_refresh_lets_old_failures_age_out(client, world):
    made = recording(world.patient, exercise(world.clinic), 1, RunStatus.FAILED)
    refresh_all()
    AnalysisRun.objects.filter(recording=made).update(
        created_at=timezone.now() - datetime.timedelta(days=30)
    )
    client.force_login(world.therapist)
    assert "Ann Example" in attention_text(client, refresh=False)  # until the beat runs
    assert "Ann Example" not in attention_text(client)
