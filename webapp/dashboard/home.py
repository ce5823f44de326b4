"""What the home page shows, read with a fixed number of queries whatever the clinic's size.

Every list is limited (or paged in memory after one bounded query), and each recording's newest
run is read with correlated subqueries instead of one query per row.
"""

from __future__ import annotations

import datetime
from typing import Any

from django.core.paginator import Page, Paginator
from django.db.models import OuterRef, QuerySet, Subquery
from django.urls import reverse
from django.utils import timezone

from webapp.accounts.models import User
from webapp.accounts.permissions import visible_patients, visible_recordings
from webapp.dashboard.precompute import read_page
from webapp.patients.adherence import patient_adherence
from webapp.patients.models import Patient, Prescription
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from webapp.recordings.reading import figure_annotations, with_figures

RECENT_RECORDINGS = 10
ACTIVE_RUNS = 20
MY_PATIENTS = 8
ATTENTION_PER_PAGE = 10
ACTIVE = (RunStatus.QUEUED, RunStatus.RUNNING)
NOT_THE_EXERCISE = "Does not show the exercise"


def with_newest_run(recordings: QuerySet[Recording]) -> QuerySet[Recording]:
    """Annotate each recording with its newest run's status, stage, progress and score, and its
    reading's stored figures (fits, repetitions, passed: `webapp.recordings.reading`)."""
    newest = AnalysisRun.objects.filter(recording_id=OuterRef("pk")).order_by("-created_at")
    return recordings.annotate(
        run_id=Subquery(newest.values("pk")[:1]),
        run_status=Subquery(newest.values("status")[:1]),
        run_stage=Subquery(newest.values("stage")[:1]),
        run_progress=Subquery(newest.values("progress")[:1]),
        run_score=Subquery(newest.values("score")[:1]),
        **figure_annotations(newest),
    )


def status_words(recording: Recording) -> str | None:
    """The list's word for the newest run: a finished analysis of a recording that does not show
    its exercise says so (it has no score), never only "Succeeded"."""
    if recording.run_status == RunStatus.SUCCEEDED and recording.run_fits is False:
        return NOT_THE_EXERCISE
    return RunStatus(recording.run_status).label if recording.run_status else None


def recent_recordings(user: User, limit: int = RECENT_RECORDINGS) -> list[Recording]:
    recordings = visible_recordings(user).select_related("patient", "exercise")
    rows = with_figures(with_newest_run(recordings).order_by("-uploaded_at")[:limit])
    for row in rows:
        row.status_words = status_words(row)
    return rows


def active_runs(user: User, limit: int = ACTIVE_RUNS) -> list[AnalysisRun]:
    """Queued and running analyses, oldest first (the ones the queue will finish next)."""
    runs = (
        AnalysisRun.objects.filter(status__in=ACTIVE, recording__in=visible_recordings(user))
        .select_related("recording__patient", "recording__exercise")
        .defer("summary", "developer_error")
        .order_by("created_at")
    )
    return list(runs[:limit])


def attention_page(user: User, page_number: Any) -> Page:
    """One page of the patients needing attention, from the stored list (two queries per page,
    whatever the clinic's size; `webapp.dashboard.precompute` keeps it up to date)."""
    if user.clinic_id is None:
        return Paginator([], ATTENTION_PER_PAGE).get_page(1)
    return read_page(user.clinic_id, page_number, ATTENTION_PER_PAGE)


def my_patients(user: User, limit: int = MY_PATIENTS) -> list[Patient]:
    """The therapist's own patients, most recently active first (the clinic's when none)."""
    patients = visible_patients(user).filter(archived_at__isnull=True)
    mine = patients.filter(therapists=user)
    chosen = mine if mine.exists() else patients
    ordered = chosen.order_by("-last_activity_at", "display_name")
    return list(ordered.only("pk", "display_name", "last_activity_at")[:limit])


def patient_plan(patient: Patient, today: datetime.date | None = None) -> dict[str, Any]:
    """The patient's current prescriptions, each with its dosage and its adherence over the last
    four weeks (`expected`, `done`), and the patient's days with data (two queries)."""
    today = today or timezone.localdate()
    prescriptions = list(
        Prescription.objects.filter(patient=patient, start_date__lte=today)
        .exclude(end_date__lt=today)
        .select_related("exercise")
        .order_by("exercise__name")
    )
    found, days = patient_adherence(patient, today, prescriptions)
    rows = [
        {
            "prescription": prescription,
            "expected": figures.last_4_weeks.sessions_prescribed,
            "done": figures.last_4_weeks.sessions_done,
        }
        for prescription, figures in zip(prescriptions, found, strict=True)
    ]
    return {"prescriptions": rows, "days_with_data": days}


def run_json(run: AnalysisRun) -> dict[str, Any]:
    recording = run.recording
    return {
        "run": str(run.pk),
        "recording": str(recording.pk),
        "url": reverse("recordings:detail", args=[recording.pk]),
        "patient": recording.patient.display_name,
        "exercise": recording.exercise.name if recording.exercise_id else None,
        "status": run.status,
        "status_label": run.get_status_display(),
        "stage": run.stage,
        "progress": run.progress,
    }


def recording_json(recording: Recording) -> dict[str, Any]:
    return {
        "recording": str(recording.pk),
        "url": reverse("recordings:detail", args=[recording.pk]),
        "patient": recording.patient.display_name,
        "exercise": recording.exercise.name if recording.exercise_id else None,
        "uploaded_at": timezone.localtime(recording.uploaded_at).strftime("%-d %b %Y %H:%M"),
        "status": recording.run_status,
        "status_label": status_words(recording),
        "progress": recording.run_progress,
        "score": None if recording.run_score is None else round(recording.run_score),
        "fits": recording.run_fits,
        "passed": recording.run_passed,
        "repetitions": recording.run_repetitions,
    }


def live_json(user: User) -> dict[str, Any]:
    """What the page polls: the analyses under way and the recent recordings' states."""
    return {
        "active": [run_json(run) for run in active_runs(user)],
        "recent": [recording_json(r) for r in recent_recordings(user)],
    }
