"""The audit log: every read and write of patient data leaves an event (who, what, when, where);
the clinic admin reads the clinic's events; nobody changes or deletes them."""

from __future__ import annotations

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.test import Client
from django.urls import reverse
from rest_framework.test import APIClient

from tests.personas import fixture_bytes, make_exercise, make_recording
from tests.webapp.test_permissions import CASES, PERSONAS, Case, url_kwargs
from webapp.accounts.models import Clinic, Role, User
from webapp.accounts.tokens import issue_token
from webapp.audit.models import AppendOnlyError, AuditEvent

# Polled every second while an analysis runs; the page that polls it is itself audited.
NOT_AUDITED = {"recordings:status"}
# Fetched by the recording page for what it shows: folded into that page view's event when the
# same user read the recording just before, an event of their own otherwise.
PAGE_PARTS = {"reports:playback", "reports:playback-bin"}


def patient_data_cases() -> list[Case]:
    """Every route of the permission matrix that names a patient or one of their recordings."""
    return [c for c in CASES if c.target in {"patient", "recording"} and c.name not in NOT_AUDITED]


@pytest.fixture
def objects(world):
    exercise = make_exercise(world.clinic)
    return {
        "patient": world.patient,
        "exercise": exercise,
        "recording": make_recording(world.patient, exercise),
    }


def allowed(case: Case, persona: str) -> bool:
    return case.expected[PERSONAS.index(persona)] < 400


def test_every_patient_data_route_writes_an_event(world, objects):
    cases = patient_data_cases()
    assert len(cases) >= 25  # the walk found the matrix's patient-data routes
    _, key = issue_token(world.therapist, "practice system")
    silent = []
    for case in cases:
        url = reverse(case.name, kwargs=url_kwargs(case.target, objects))
        for persona, user in (("therapist", world.therapist), ("patient", world.patient_user)):
            if not allowed(case, persona):
                continue
            client = APIClient()
            if case.name.startswith(("api-", "reports:api-")) and persona == "therapist":
                client.credentials(HTTP_AUTHORIZATION=f"Token {key}")
            else:
                client.force_login(user)
            before = AuditEvent.objects.count()
            response = getattr(client, case.method)(url, REMOTE_ADDR="10.1.2.3")
            events = AuditEvent.objects.order_by("id")[before:]
            mine = [
                e
                for e in events
                if e.patient_id == world.patient.pk
                and e.user_id == user.pk
                and e.ip_address == "10.1.2.3"
                and e.at is not None
            ]
            if case.name in PAGE_PARTS and not mine:
                mine = read_of(user, objects["recording"])  # the page's event, written before
            if response.status_code >= 400 or not mine:
                silent.append(f"{persona} {case.method.upper()} {url} → {response.status_code}")
    assert silent == []


def read_of(user, recording) -> list[AuditEvent]:
    events = AuditEvent.objects.filter(user=user, action="read", object_id=str(recording.pk))
    return list(events)


def test_token_reads_name_the_token(world, objects):
    token, key = issue_token(world.therapist, "practice system")
    client = APIClient()
    client.credentials(HTTP_AUTHORIZATION=f"Token {key}")
    client.get(f"/api/v1/patients/{world.patient.pk}/progress/")
    event = AuditEvent.objects.get(patient_id=world.patient.pk)
    assert (event.action, event.via, event.username) == (
        "read",
        f"token {token.prefix}",
        "therapist",
    )


def test_writes_are_logged_with_their_kind(world, objects, client):
    client.force_login(world.therapist)
    client.post(reverse("patients:create"), {"display_name": "Dee New"})
    edit = reverse("patients:edit", kwargs={"pk": world.patient.pk})
    client.post(edit, {"display_name": "Ann Renamed"})
    api = APIClient()
    api.force_authenticate(world.therapist)
    upload = SimpleUploadedFile("take.bvh.gz", fixture_bytes("reps/m01_s01_e03.bvh.gz"))
    answer = api.post(
        "/api/v1/recordings/",
        {"patient": str(world.patient.pk), "exercise": str(objects["exercise"].pk), "file": upload},
        format="multipart",
    )
    assert answer.status_code == 201
    kinds = set(AuditEvent.objects.values_list("action", "object_type"))
    assert {("create", "Patient"), ("update", "Patient"), ("create", "Recording")} <= kinds
    assert ("create", "AnalysisRun") in kinds


def test_writes_outside_a_request_are_not_attributed(world, objects):
    before = AuditEvent.objects.count()
    make_recording(world.patient, objects["exercise"])  # as a worker or a command would
    assert AuditEvent.objects.count() == before


def test_events_are_append_only(world, objects, client):
    client.force_login(world.therapist)
    client.get(reverse("patients:detail", kwargs={"pk": world.patient.pk}))
    event = AuditEvent.objects.get()
    event.username = "someone else"
    with pytest.raises(AppendOnlyError):
        event.save()
    with pytest.raises(AppendOnlyError):
        event.delete()
    with pytest.raises(AppendOnlyError):
        AuditEvent.objects.filter(pk=event.pk).update(username="x")
    with pytest.raises(AppendOnlyError):
        AuditEvent.objects.all().delete()
    assert AuditEvent.objects.get().username == "therapist"


def test_admin_site_shows_events_read_only(world, objects, client):
    client.force_login(world.therapist)
    client.get(reverse("patients:detail", kwargs={"pk": world.patient.pk}))
    event = AuditEvent.objects.get()
    root = User.objects.create_superuser("root", "root@example.org", "a-long-root-password-1")
    client.force_login(root)
    change = reverse("admin:audit_auditevent_change", args=[event.pk])
    assert client.get(change).status_code == 200  # viewing is allowed
    assert client.post(change, {"username": "x"}).status_code == 403
    delete = reverse("admin:audit_auditevent_delete", args=[event.pk])
    assert client.post(delete, {"post": "yes"}).status_code == 403
    assert client.get(reverse("admin:audit_auditevent_add")).status_code == 403
    assert AuditEvent.objects.get().username == "therapist"


def read_as(user, patient, times: int = 1) -> None:
    client = Client()
    client.force_login(user)
    for _ in range(times):
        client.get(reverse("patients:detail", kwargs={"pk": patient.pk}))


def test_clinic_admin_page_filters_and_paginates(world, objects, client):
    read_as(world.therapist, world.patient, times=3)
    read_as(world.colleague, world.other_patient, times=52)
    read_as(world.outsider, world.outsider_patient)
    client.force_login(world.clinic_admin)
    page = client.get(reverse("audit:events"))
    assert page.status_code == 200
    assert page.context["page"].paginator.count == 55  # not the other clinic's event
    assert len(page.context["page"].object_list) == 50
    second = client.get(reverse("audit:events"), {"page": 2})
    assert len(second.context["page"].object_list) == 5
    by_patient = client.get(reverse("audit:events"), {"patient": world.patient.pk})
    assert by_patient.context["page"].paginator.count == 3
    assert "Ann Example" in by_patient.content.decode()
    by_user = client.get(reverse("audit:events"), {"user": world.colleague.pk, "page": 2})
    assert by_user.context["page"].paginator.count == 52
    assert "user=" in by_user.context["filters"]


def test_other_clinics_admin_sees_none_of_these_events(world, objects, client):
    read_as(world.therapist, world.patient)
    other_admin = User.objects.create_user(
        "south-admin",
        password="x-long-password-9",
        clinic=world.other_clinic,
        role=Role.CLINIC_ADMIN,
    )
    client.force_login(other_admin)
    assert client.get(reverse("audit:events")).context["page"].paginator.count == 0
    # Filtering by a patient of another clinic is refused by the form, not answered.
    other = client.get(reverse("audit:events"), {"patient": world.patient.pk})
    assert other.context["page"].paginator.count == 0
    assert Clinic.objects.count() == 2
