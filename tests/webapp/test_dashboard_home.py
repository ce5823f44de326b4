"""The home page: patients needing attention, recent recordings, analyses under way, and the
patient's own simplified home; with a bounded number of queries whatever the clinic's size."""

from __future__ import annotations

import datetime
import uuid

import pytest
from django.urls import reverse
from django.utils import timezone

from webapp.dashboard.precompute import refresh_all
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient, Prescription
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from webapp.recordings.reading import build, store_missing

HOME = "dashboard:home"


def exercise(clinic, name: str = "Deep squat") -> Exercise:
    return Exercise.objects.create(clinic=clinic, name=name, tutor_file="tutors/none.bvh.gz")


def recording(patient, exercise, days_ago: float, status=RunStatus.SUCCEEDED, score=None, **run):
    """A recording uploaded `days_ago` days ago with one run (no file is read by the home page)."""
    made = Recording.objects.create(
        clinic=patient.clinic,
        patient=patient,
        exercise=exercise,
        file="recordings/none.bvh.gz",
        checksum=uuid.uuid4().hex,
    )
    uploaded = timezone.now() - datetime.timedelta(days=days_ago)
    Recording.objects.filter(pk=made.pk).update(uploaded_at=uploaded)
    summary = {"score": score} if score is not None else {}
    created = AnalysisRun.objects.create(recording=made, status=status, summary=summary, **run)
    build(created)  # its reading, as a run that ends has one
    made.uploaded_at = uploaded
    return made


def prescribe(patient, exercise, per_week: int = 3, days_ago: int = 60) -> Prescription:
    start = timezone.localdate() - datetime.timedelta(days=days_ago)
    return Prescription.objects.create(
        patient=patient, exercise=exercise, sessions_per_week=per_week, start_date=start
    )


def attention_text(client, refresh: bool = True) -> str:
    """The attention section, after the refresh beat makes (data here is written with the ORM,
    not through the workers that refresh on write)."""
    if refresh:
        refresh_all()
    response = client.get(reverse(HOME))
    assert response.status_code == 200
    page = response.content.decode()
    start = page.index('id="attention"')
    return page[start : page.index("</section>", start)]


@pytest.fixture
def therapist_client(client, world):
    client.force_login(world.therapist)
    return client


def test_failed_newest_run_puts_the_patient_on_the_list(therapist_client, world):
    squat = exercise(world.clinic)
    failed = recording(world.patient, squat, 1, RunStatus.FAILED, user_error="Too short")
    section = attention_text(therapist_client)
    assert "Ann Example" in section
    assert "failed analysis" in section
    assert reverse("recordings:detail", args=[failed.pk]) in section


def test_failure_fixed_by_a_rerun_is_not_flagged(therapist_client, world):
    squat = exercise(world.clinic)
    rec = recording(world.patient, squat, 1, RunStatus.FAILED)
    AnalysisRun.objects.create(recording=rec, status=RunStatus.SUCCEEDED, summary={"score": 80})
    assert "Ann Example" not in attention_text(therapist_client)


def test_old_failure_is_not_flagged(therapist_client, world):
    recording(world.patient, exercise(world.clinic), 30, RunStatus.FAILED)
    run = AnalysisRun.objects.get()
    AnalysisRun.objects.filter(pk=run.pk).update(
        created_at=timezone.now() - datetime.timedelta(days=30)
    )
    assert "Ann Example" not in attention_text(therapist_client)


def test_falling_score_is_flagged_with_the_drop(therapist_client, world):
    squat = exercise(world.clinic)
    for days_ago, score in ((20, 80), (15, 84), (10, 82), (2, 60)):
        recording(world.patient, squat, days_ago, score=score)
    section = attention_text(therapist_client)
    assert "reason-falling" in section
    assert "score 60, down 22 from 82" in section


def test_steady_or_rising_scores_are_not_flagged(therapist_client, world):
    squat = exercise(world.clinic)
    for days_ago, score in ((20, 60), (15, 62), (10, 66), (2, 75)):
        recording(world.patient, squat, days_ago, score=score)
    # A single low score with nothing before it is no trend either.
    recording(world.other_patient, squat, 1, score=20)
    assert "reason-falling" not in attention_text(therapist_client)


def test_missed_sessions_are_flagged_and_kept_ones_are_not(therapist_client, world):
    squat, sit = exercise(world.clinic), exercise(world.clinic, "Sit to stand")
    prescribe(world.patient, squat, per_week=3)
    prescribe(world.other_patient, sit, per_week=2)
    recording(world.patient, squat, 3, score=80)
    for days_ago in (1, 4, 8, 12):
        recording(world.other_patient, sit, days_ago, score=80)
    section = attention_text(therapist_client)
    assert "Deep squat: 1 of 6 prescribed sessions in the last 14 days" in section
    assert "Bob Example" not in section


def test_other_clinics_and_archived_patients_stay_out(client, world):
    squat = exercise(world.clinic)
    recording(world.patient, squat, 1, RunStatus.FAILED)
    elsewhere = exercise(world.other_clinic)
    recording(world.outsider_patient, elsewhere, 1, RunStatus.FAILED)
    client.force_login(world.outsider)
    section = attention_text(client)
    assert "Cy Elsewhere" in section and "Ann Example" not in section
    Patient.objects.filter(pk=world.outsider_patient.pk).update(archived_at=timezone.now())
    assert "Cy Elsewhere" not in attention_text(client)


def test_recent_recordings_show_status_and_score(therapist_client, world):
    squat = exercise(world.clinic)
    recording(world.patient, squat, 2, score=73.4)
    recording(world.other_patient, squat, 1, RunStatus.RUNNING, stage="alignment", progress=40)
    page = therapist_client.get(reverse(HOME)).content.decode()
    recent = page[page.index('id="recent"') :]
    assert "Succeeded" in recent and ">73<" in recent
    assert "Running 40%" in recent
    active = page[page.index('id="active-runs"') : page.index('id="my-patients"')]
    assert "Bob Example · Deep squat" in active
    assert "Running · alignment" in active and "width: 40%" in active
    assert "Ann Example" not in active


def test_live_json_reports_runs_under_way(therapist_client, world):
    squat = exercise(world.clinic)
    rec = recording(world.patient, squat, 0, RunStatus.QUEUED)
    data = therapist_client.get(reverse(HOME), {"format": "json"}).json()
    assert [run["recording"] for run in data["active"]] == [str(rec.pk)]
    AnalysisRun.objects.filter(recording=rec).update(
        status=RunStatus.RUNNING, stage="landmarks", progress=55
    )
    run = therapist_client.get(reverse(HOME), {"format": "json"}).json()["active"][0]
    assert (run["status"], run["stage"], run["progress"]) == ("running", "landmarks", 55)
    AnalysisRun.objects.filter(recording=rec).update(
        status=RunStatus.SUCCEEDED, progress=100, summary={"score": 91}
    )
    data = therapist_client.get(reverse(HOME), {"format": "json"}).json()
    assert data["active"] == []
    assert data["recent"][0]["status"] == "succeeded" and data["recent"][0]["score"] == 91


def test_patient_home_shows_own_prescriptions_and_recordings(client, world):
    squat = exercise(world.clinic)
    prescribe(world.patient, squat, per_week=2)
    recording(world.patient, squat, 1, score=88)
    recording(world.other_patient, squat, 1, score=12)
    recording(world.other_patient, squat, 0, RunStatus.RUNNING, progress=10)
    client.force_login(world.patient_user)
    page = client.get(reverse(HOME)).content.decode()
    assert "Your exercises" in page and "Deep squat" in page
    assert "Last 4 weeks: 1 of 8 sessions done" in page
    assert ">88<" in page and ">12<" not in page
    assert "Bob Example" not in page
    assert "Patients needing attention" not in page
    data = client.get(reverse(HOME), {"format": "json"}).json()
    assert data["active"] == []
    assert {r["score"] for r in data["recent"]} == {88}


def fill_clinic(world, patients: int, recordings_each: int) -> None:
    """Many patients, each with prescriptions, scored recordings, a failure and a running run."""
    exercises = [exercise(world.clinic, f"Exercise {i}") for i in range(3)]
    now = timezone.now()
    made = Patient.objects.bulk_create(
        Patient(clinic=world.clinic, display_name=f"Patient {i:03d}") for i in range(patients)
    )
    recs, runs, prescriptions = [], [], []
    for i, patient in enumerate(made):
        patient.therapists.add(world.therapist)
        prescriptions.append(
            Prescription(
                patient=patient,
                exercise=exercises[i % 3],
                sessions_per_week=3,
                start_date=(now - datetime.timedelta(days=40)).date(),
            )
        )
        for j in range(recordings_each):
            rec = Recording(
                clinic=world.clinic,
                patient=patient,
                exercise=exercises[i % 3],
                file="recordings/none.bvh.gz",
                checksum=uuid.uuid4().hex,
            )
            recs.append(rec)
            last = j == recordings_each - 1
            status = (
                [RunStatus.SUCCEEDED, RunStatus.FAILED, RunStatus.RUNNING][i % 3]
                if last
                else RunStatus.SUCCEEDED
            )
            runs.append(
                AnalysisRun(
                    recording=rec, status=status, progress=50, summary={"score": 90 - 10 * j}
                )
            )
    Prescription.objects.bulk_create(prescriptions)
    Recording.objects.bulk_create(recs)
    AnalysisRun.objects.bulk_create(runs)
    store_missing(AnalysisRun.objects.all())  # a bulk load stores its runs' readings too
    for j in range(recordings_each):
        Recording.objects.filter(pk__in=[r.pk for r in recs[j::recordings_each]]).update(
            uploaded_at=now - datetime.timedelta(days=3 * (recordings_each - j))
        )


# Session, user, two-factor device and clinic (the layout), then: recent recordings, runs under
# way, attention (the stored list: its count and one page with names), your patients (two). The
# same cap holds for a clinic of any size.
THERAPIST_HOME_QUERIES = 11
PATIENT_HOME_QUERIES = 10  # + the newest run's result in lay words (issue 24)


@pytest.mark.parametrize("patients", [3, 90])
def test_therapist_home_queries_do_not_grow_with_the_clinic(
    client, world, django_assert_max_num_queries, patients
):
    fill_clinic(world, patients, recordings_each=4)
    refresh_all()
    client.force_login(world.therapist)
    with django_assert_max_num_queries(THERAPIST_HOME_QUERIES):
        response = client.get(reverse(HOME))
    page = response.content.decode()
    assert page.count('class="attention-item"') == min(10, patients)  # a page at most
    assert page.count("<tr data-recording=") == 10
    assert 'data-run="' in page
    with django_assert_max_num_queries(THERAPIST_HOME_QUERIES):
        response = client.get(reverse(HOME), {"attention_page": 2})
    with django_assert_max_num_queries(6):
        data = client.get(reverse(HOME), {"format": "json"}).json()
    assert len(data["active"]) == min(20, patients // 3)


def test_patient_home_queries_are_bounded(client, world, django_assert_max_num_queries):
    squat = exercise(world.clinic)
    for name in ("Sit to stand", "Lunge", "Bridge"):
        prescribe(world.patient, exercise(world.clinic, name))
    prescribe(world.patient, squat)
    for days_ago in range(12):
        recording(world.patient, squat, days_ago, score=70 + days_ago)
    client.force_login(world.patient_user)
    with django_assert_max_num_queries(PATIENT_HOME_QUERIES):
        response = client.get(reverse(HOME))
    assert response.content.decode().count("<tr data-recording=") == 10
