"""Query counts per page stay flat as a clinic grows (the large-clinic bench measures latency).

A small clinic from `fill_large_clinic` (the same generator as the 10,000-patient bench): each
page's number of SQL queries must not depend on how many patients, recordings or runs there are.
"""

from __future__ import annotations

import json

import pytest
from django.core.management import call_command
from django.db import connection
from django.db.models import Count
from django.test.utils import CaptureQueriesContext

from webapp.accounts.models import Clinic, User
from webapp.dashboard.models import ProgressPoint
from webapp.patients.models import Patient
from webapp.patients.progress_store import store_points
from webapp.recordings.models import AnalysisRun

CLINIC = "Query-count clinic"


@pytest.fixture
def clinic(db):
    call_command("fill_large_clinic", patients=30, runs=800, therapists=2, clinic=CLINIC)
    return Clinic.objects.get(name=CLINIC)


@pytest.fixture
def therapist_client(client, clinic):
    client.force_login(User.objects.filter(clinic=clinic).order_by("username").first())
    return client


def patients_by_runs(clinic):
    """The patients with the fewest and the most runs among those with one prescription (the
    patient page reads adherence with one query per prescription, a handful at most)."""
    rows = (
        AnalysisRun.objects.filter(recording__clinic=clinic)
        .annotate(prescriptions=Count("recording__patient__prescriptions", distinct=True))
        .filter(prescriptions=1)
        .values("recording__patient")
        .annotate(n=Count("id", distinct=True))
        .order_by("n")
    )
    ids = [r["recording__patient"] for r in rows]
    return Patient.objects.get(pk=ids[0]), Patient.objects.get(pk=ids[-1])


def queries_for(client, url: str) -> int:
    with CaptureQueriesContext(connection) as queries:
        response = client.get(url)
    assert response.status_code == 200, url
    return len(queries)


def test_fill_makes_the_clinic_asked_for(clinic):
    assert Patient.objects.filter(clinic=clinic).count() == 30
    runs = AnalysisRun.objects.filter(recording__clinic=clinic)
    assert runs.count() == 800
    summary = runs.filter(status="succeeded").first().summary
    assert 0 <= summary["score"] <= 100
    assert len(summary["repetitions"]) == summary["repetition_count"]


def test_fill_stores_every_succeeded_runs_progress_point_as_a_worker_would(clinic):
    succeeded = AnalysisRun.objects.filter(recording__clinic=clinic, status="succeeded")
    filled = {p.run_id: p for p in ProgressPoint.objects.filter(run__recording__clinic=clinic)}
    assert len(filled) == succeeded.count() > 0
    ProgressPoint.objects.all().delete()
    from_summaries = store_points(succeeded.values_list("pk", flat=True))  # read back, rendered
    texts = ("page", "api", "joints")

    def parsed(point):
        # PostgreSQL's jsonb reorders object keys on the way back; the figures must be equal.
        return [json.loads(getattr(point, f)) for f in texts] + [point.clinical]

    for run_id, point in from_summaries.items():
        assert parsed(point) == parsed(filled[run_id])


def test_progress_answers_never_read_a_summary(therapist_client, clinic):
    """The long history's progress comes from the stored points: no run's summary is read."""
    _, many = patients_by_runs(clinic)
    for page in ("/patients/{id}/progress.json", "/api/v1/patients/{id}/progress/"):
        with CaptureQueriesContext(connection) as queries:
            response = therapist_client.get(page.format(id=many.pk))
        points = response.json()["points"]
        assert len(points) == many.recordings.filter(runs__status="succeeded").distinct().count()
        assert not [q["sql"] for q in queries if "summary" in q["sql"]], page


# Most SQL queries each page may make (session, user, audit event and the page's own reads),
# with a little room for features that add a query; an N+1 query breaks these bounds and the
# equality checks below at once.
PATIENT_PAGES = {
    "/patients/{id}/": 18,  # + the pain chart's scores and the live-session exercises
    "/patients/{id}/progress.json": 8,
    "/api/v1/patients/{id}/recordings/": 10,
    "/api/v1/patients/{id}/progress/": 8,
}
LIST_PAGES = {"/": 18, "/patients/": 8, "/patients/?page=2": 8, "/api/v1/patients/": 7}


def test_patient_pages_make_as_many_queries_for_a_long_history_as_for_a_short_one(
    therapist_client, clinic, django_assert_max_num_queries
):
    few, many = patients_by_runs(clinic)
    assert many.recordings.count() > 3 * few.recordings.count()
    for page, most in PATIENT_PAGES.items():
        with django_assert_max_num_queries(most):
            short = queries_for(therapist_client, page.format(id=few.pk))
        with django_assert_max_num_queries(most):
            long = queries_for(therapist_client, page.format(id=many.pk))
        assert short == long, page


def test_list_pages_make_as_many_queries_for_twice_the_patients(
    therapist_client, clinic, django_assert_max_num_queries
):
    before = {page: queries_for(therapist_client, page) for page in LIST_PAGES}
    call_command(
        "fill_large_clinic", patients=30, runs=300, therapists=1, clinic=CLINIC,
        into_existing=True, seed=1,
    )  # fmt: skip
    assert Patient.objects.filter(clinic=clinic).count() == 60
    for page, most in LIST_PAGES.items():
        with django_assert_max_num_queries(most):
            after = queries_for(therapist_client, page)
        assert after == before[page], page
