"""Live sessions from the therapist's pages: started on the patient page, listed on the home page
while under way (and left off once ended or silent), watched read-only by the clinic's
therapists; names on the attention list are links to the patient page."""

from __future__ import annotations

import datetime
import re
import uuid

import pytest
from django.urls import reverse
from django.utils import timezone

from webapp.audit.models import AuditEvent
from webapp.dashboard.precompute import refresh_all
from webapp.exercises.models import Exercise, ExerciseModel, ModelStatus
from webapp.live.models import LiveSession, LiveStatus
from webapp.live.services import STALE_AFTER
from webapp.patients.models import Prescription
from webapp.recordings.models import AnalysisRun, Recording, RunStatus


def exercise(clinic, name: str, with_model: bool = True) -> Exercise:
    made = Exercise.objects.create(clinic=clinic, name=name, tutor_file="tutors/none.bvh.gz")
    if with_model:
        row = ExerciseModel.objects.create_next_version(made, status=ModelStatus.READY)
        Exercise.objects.filter(pk=made.pk).update(active_model=row)
    return made


def prescribe(patient, exercise: Exercise, ended: bool = False) -> Prescription:
    today = timezone.localdate()
    return Prescription.objects.create(
        patient=patient,
        exercise=exercise,
        start_date=today - datetime.timedelta(days=30),
        end_date=today - datetime.timedelta(days=1) if ended else None,
    )


@pytest.fixture
def squat(world) -> Exercise:
    made = exercise(world.clinic, "Deep squat")
    prescribe(world.patient, made)
    return made


@pytest.fixture
def therapist(client, world):
    client.force_login(world.therapist)
    return client


def start(client, patient, exercise: Exercise):
    return client.post(f"/live/start/{patient.pk}/", {"exercise": str(exercise.pk)})


def home_section(client) -> str:
    page = client.get(reverse("dashboard:home"))
    assert page.status_code == 200
    html = page.content.decode()
    begin = html.index('id="live-under-way"')
    return html[begin : html.index("</section>", begin)]


def test_patient_page_offers_only_prescribed_exercises_with_a_model(therapist, world, squat):
    prescribe(world.patient, exercise(world.clinic, "Lunge", with_model=False))
    prescribe(world.patient, exercise(world.clinic, "Bridge"), ended=True)
    exercise(world.clinic, "Plank")  # has a model, not prescribed
    html = therapist.get(f"/patients/{world.patient.pk}/").content.decode()
    form = html[html.index('id="live-start"') :]
    form = form[: form.index("</section>")]
    assert "Start a live session" in form
    assert re.findall(r"<option [^>]*>([^<]+)</option>", form) == ["Deep squat"]


def test_starting_from_the_patient_page_creates_the_session_and_opens_its_page(
    therapist, world, squat
):
    response = start(therapist, world.patient, squat)
    live = LiveSession.objects.get()
    assert response.status_code == 302 and response.url == f"/live/{live.pk}/"
    assert (live.patient, live.exercise, live.created_by) == (world.patient, squat, world.therapist)
    assert live.status == LiveStatus.OPEN and live.clinic == world.clinic
    created = AuditEvent.objects.get(action="create", object_type="LiveSession")
    assert created.object_id == str(live.pk) and created.patient_id == world.patient.pk
    page = therapist.get(response.url).content.decode()
    assert live.ws_path in page and f"--session {live.pk}" in page


def test_an_exercise_not_offered_starts_nothing(therapist, world, squat):
    lunge = exercise(world.clinic, "Lunge", with_model=False)
    prescribe(world.patient, lunge)
    for chosen in (lunge, exercise(world.clinic, "Plank")):
        response = start(therapist, world.patient, chosen)
        assert response.status_code == 302
        assert response.url == f"/patients/{world.patient.pk}/"
    assert not LiveSession.objects.exists()


@pytest.mark.parametrize(("who", "status"), [("outsider", 404), ("patient_user", 403)])
def test_only_the_clinics_therapists_start_sessions(client, world, squat, who, status):
    client.force_login(getattr(world, who))
    assert start(client, world.patient, squat).status_code == status
    assert not LiveSession.objects.exists()


def test_home_lists_a_session_under_way_with_a_working_watch_link(therapist, world, squat):
    start(therapist, world.patient, squat)
    live = LiveSession.objects.get()
    LiveSession.objects.filter(pk=live.pk).update(
        status=LiveStatus.LIVE, repetitions=3, last_frame_at=timezone.now()
    )
    section = home_section(therapist)
    row = section[section.index(f'data-live="{live.pk}"') :]
    assert f'href="/patients/{world.patient.pk}/">Ann Example</a>' in row
    assert "Deep squat" in row and '<td class="num">3</td>' in row
    watch = f"/live/{live.pk}/watch/"
    assert f'href="{watch}"' in row
    page = therapist.get(watch)
    assert page.status_code == 200
    html = page.content.decode()
    assert f'data-ws="{live.ws_path}?watch=1"' in html and 'id="rep-count">3<' in html
    assert AuditEvent.objects.filter(action="read", object_id=str(live.pk)).count() == 1


def set_session(live: LiveSession, **fields) -> None:
    LiveSession.objects.filter(pk=live.pk).update(**fields)


def test_ended_silent_and_replayed_sessions_leave_the_list(therapist, world, squat):
    now = timezone.now()
    just_inside = now - STALE_AFTER + datetime.timedelta(seconds=20)
    just_outside = now - STALE_AFTER - datetime.timedelta(seconds=20)
    sessions = {}
    for name in ("streaming", "waiting", "ended", "silent", "never-started", "replay"):
        start(therapist, world.patient, squat)
        sessions[name] = LiveSession.objects.order_by("-created_at").first()
    set_session(sessions["streaming"], status=LiveStatus.LIVE, last_frame_at=just_inside)
    set_session(sessions["ended"], status=LiveStatus.ENDED, last_frame_at=now)
    set_session(sessions["silent"], status=LiveStatus.LIVE, last_frame_at=just_outside)
    set_session(sessions["never-started"], created_at=just_outside)
    recording = Recording.objects.create(
        clinic=world.clinic, patient=world.patient, exercise=squat,
        file="recordings/none.bvh.gz", checksum=uuid.uuid4().hex,
    )  # fmt: skip
    set_session(sessions["replay"], replay_of=recording)
    section = home_section(therapist)
    listed = {name for name, live in sessions.items() if f'data-live="{live.pk}"' in section}
    assert listed == {"streaming", "waiting"}


def test_another_clinics_therapist_and_patients_cannot_watch(client, world, squat):
    live = LiveSession.objects.create(
        clinic=world.clinic, patient=world.patient, exercise=squat, status=LiveStatus.LIVE
    )
    answers = {}
    for user in (world.outsider, world.patient_user, world.other_patient_user):
        client.force_login(user)
        answers[user.username] = client.get(f"/live/{live.pk}/watch/").status_code
    assert answers == {"outsider": 404, "patient": 403, "other-patient": 403}
    client.force_login(world.outsider)
    assert f'data-live="{live.pk}"' not in home_section(client)
    client.force_login(world.colleague)
    assert client.get(f"/live/{live.pk}/watch/").status_code == 200


def test_names_on_the_attention_list_link_to_the_patient_page(therapist, world, squat):
    for patient in (world.patient, world.other_patient):
        failed = Recording.objects.create(
            clinic=world.clinic, patient=patient, exercise=squat,
            file="recordings/none.bvh.gz", checksum=uuid.uuid4().hex,
        )  # fmt: skip
        AnalysisRun.objects.create(recording=failed, status=RunStatus.FAILED, user_error="short")
    refresh_all()
    html = therapist.get(reverse("dashboard:home")).content.decode()
    begin = html.index('id="attention"')
    section = html[begin : html.index("</section>", begin)]
    for patient in (world.patient, world.other_patient):
        link = f'href="/patients/{patient.pk}/">{patient.display_name}</a>'
        assert link in section, patient.display_name
