"""Invitations and password links (issue 23, item 1): one-time links that expire, stored hashed,
e-mailed when an address is given; who may invite whom; audited."""

from __future__ import annotations

import hashlib
import re
from datetime import timedelta

import pytest
from django.core import mail
from django.test import Client
from django.utils import timezone
from rest_framework.test import APIClient

from tests.personas import PASSWORD
from webapp.accounts.models import Invitation, Role, User
from webapp.audit.models import AuditEvent
from webapp.patients.models import Patient

NEW_PASSWORD = "a-fresh-secret-for-work-61"


def api_as(user: User) -> APIClient:
    client = APIClient()
    client.force_authenticate(user)
    return client


def invite(user: User, **body):
    return api_as(user).post("/api/v1/invitations/", body, format="json")


@pytest.fixture
def new_patient(world) -> Patient:
    """A patient of the therapist's with no login yet."""
    patient = Patient.objects.create(clinic=world.clinic, display_name="Dee Newcomer")
    patient.therapists.add(world.therapist)
    return patient


def accept(url: str, username: str, password: str = NEW_PASSWORD, client: Client | None = None):
    client = client or Client()
    body = {"username": username, "password1": password, "password2": password}
    return client, client.post(url, body)


def test_admin_invites_a_therapist_who_accepts_and_is_logged_in(world):
    before = timezone.now()
    answer = invite(world.clinic_admin, role="therapist")
    assert answer.status_code == 201, answer.content
    body = answer.json()
    assert set(body) == {"id", "url", "expires_at"}
    assert body["url"].startswith("/accounts/invitation/")
    expires = Invitation.objects.get(pk=body["id"]).expires_at
    assert timedelta(days=7) <= expires - before < timedelta(days=7, minutes=1)
    assert body["expires_at"] == expires.strftime("%Y-%m-%dT%H:%M:%SZ")

    form = Client().get(body["url"])
    assert form.status_code == 200
    for field in ("username", "password1", "password2"):
        assert f'name="{field}"' in form.content.decode()
    client, answer = accept(body["url"], "new-therapist")
    assert answer.status_code == 302 and answer["Location"] == "/"
    user = User.objects.get(username="new-therapist")
    assert (user.role, user.clinic_id, user.is_active) == (Role.THERAPIST, world.clinic.pk, True)
    assert "Welcome, new-therapist" in client.get("/").content.decode()  # logged in: home page
    assert Client().login(username="new-therapist", password=NEW_PASSWORD)


def test_a_used_link_answers_410_and_creates_nothing_more(world):
    url = invite(world.clinic_admin, role="admin").json()["url"]
    accept(url, "first-admin")
    assert User.objects.get(username="first-admin").role == Role.CLINIC_ADMIN
    assert Client().get(url).status_code == 410
    _, again = accept(url, "second-admin")
    assert again.status_code == 410
    assert not User.objects.filter(username="second-admin").exists()


def test_an_expired_link_answers_410(world):
    body = invite(world.clinic_admin, role="therapist").json()
    Invitation.objects.filter(pk=body["id"]).update(
        expires_at=timezone.now() - timedelta(seconds=1)
    )
    assert Client().get(body["url"]).status_code == 410
    _, answer = accept(body["url"], "too-late")
    assert answer.status_code == 410 and not User.objects.filter(username="too-late").exists()


def test_an_unknown_link_answers_404(db):
    assert Client().get("/accounts/invitation/not-a-real-key/").status_code == 404


def test_only_a_hash_of_the_link_is_stored(world):
    body = invite(world.clinic_admin, role="therapist").json()
    key = body["url"].rstrip("/").rsplit("/", 1)[1]
    row = Invitation.objects.get(pk=body["id"])
    assert len(key) >= 40 and row.key_hash == hashlib.sha256(key.encode()).hexdigest()


def test_a_therapist_invites_their_own_patient_whose_login_is_linked(world, new_patient):
    answer = invite(world.therapist, role="patient", patient=str(new_patient.pk))
    assert answer.status_code == 201, answer.content
    client, accepted = accept(answer.json()["url"], "dee")
    assert accepted.status_code == 302
    new_patient.refresh_from_db()
    assert new_patient.user.username == "dee" and new_patient.user.role == Role.PATIENT
    assert "Welcome, Dee Newcomer" in client.get("/").content.decode()  # the patient's home


@pytest.mark.parametrize(
    ("who", "body", "status"),
    [
        ("therapist", {"role": "therapist"}, 403),
        ("therapist", {"role": "admin"}, 403),
        ("colleague", {"role": "patient", "patient": "new"}, 403),  # not their patient
        ("patient_user", {"role": "patient", "patient": "new"}, 403),
        ("outsider", {"role": "patient", "patient": "new"}, 404),  # another clinic's patient
        ("clinic_admin", {"role": "patient"}, 400),  # which patient?
        ("clinic_admin", {"role": "patient", "patient": "ann"}, 400),  # already has a login
        ("clinic_admin", {"role": "nurse"}, 400),
    ],
)
def test_who_may_invite_whom(world, new_patient, who, body, status):
    ids = {"new": str(new_patient.pk), "ann": str(world.patient.pk)}
    body = {k: ids.get(v, v) for k, v in body.items()}
    answer = invite(getattr(world, who), **body)
    assert answer.status_code == status, answer.content
    assert Invitation.objects.count() == 0


def test_anonymous_cannot_invite(world):
    assert APIClient().post("/api/v1/invitations/", {"role": "therapist"}).status_code == 401


def test_the_link_is_mailed_when_an_address_is_given(world):
    invite(world.clinic_admin, role="therapist")
    assert mail.outbox == []
    body = invite(world.clinic_admin, role="therapist", email="eve@example.org").json()
    assert len(mail.outbox) == 1 and mail.outbox[0].to == ["eve@example.org"]
    assert f"http://testserver{body['url']}" in mail.outbox[0].body
    accept(body["url"], "eve")
    assert User.objects.get(username="eve").email == "eve@example.org"


def test_taken_username_and_differing_passwords_are_refused_and_the_link_kept(world):
    url = invite(world.clinic_admin, role="therapist").json()["url"]
    _, taken = accept(url, "Therapist")  # case aside, the persona's name
    assert taken.status_code == 200 and "This username is taken" in taken.content.decode()
    differing = Client().post(
        url, {"username": "fred", "password1": NEW_PASSWORD, "password2": NEW_PASSWORD + "x"}
    )
    assert "The two passwords differ" in differing.content.decode()
    _, weak = accept(url, "fred", password="12345678")
    assert weak.status_code == 200 and not User.objects.filter(username="fred").exists()
    _, good = accept(url, "fred")
    assert good.status_code == 302


def test_invitations_and_acceptances_are_audited(world, new_patient):
    body = invite(world.therapist, role="patient", patient=str(new_patient.pk)).json()
    made = AuditEvent.objects.get(object_type="Invitation")
    assert (made.action, made.user, made.patient_id) == ("create", world.therapist, new_patient.pk)
    assert made.object_id == body["id"] and made.clinic_id == world.clinic.pk
    accept(body["url"], "dee")
    joined = AuditEvent.objects.get(object_type="User")
    assert (joined.action, joined.username, joined.patient_id) == ("create", "dee", new_patient.pk)


def team_client(world) -> Client:
    client = Client()
    client.force_login(world.clinic_admin)
    return client


def shown_link(html: str) -> str:
    match = re.search(r'id="new-link"[^>]*value="http://testserver(/[^"]+)"', html)
    assert match, html
    return match.group(1)


def test_admin_invites_from_the_team_page(world, new_patient):
    client = team_client(world)
    page = client.get("/accounts/team/")
    assert page.status_code == 200 and "Dee Newcomer" in page.content.decode()
    answer = client.post("/accounts/team/", {"role": "patient", "patient": str(new_patient.pk)})
    url = shown_link(answer.content.decode())
    accept(url, "dee")
    new_patient.refresh_from_db()
    assert new_patient.user.username == "dee"
    missing = client.post("/accounts/team/", {"role": "patient"})
    assert "Choose the patient" in missing.content.decode()


def test_team_page_is_for_clinic_admins_only(world, client):
    for user in (world.therapist, world.patient_user):
        client.force_login(user)
        assert client.get("/accounts/team/").status_code == 403
    assert 'href="/accounts/team/"' in team_client(world).get("/").content.decode()


def test_invite_button_on_the_patient_page_for_the_patients_therapist(world, new_patient):
    page = f"/patients/{new_patient.pk}/"
    invite_page = f"/accounts/invite/patient/{new_patient.pk}/"
    client = Client()
    client.force_login(world.colleague)
    assert invite_page not in client.get(page).content.decode()
    assert client.post(invite_page).status_code == 403
    client.force_login(world.therapist)
    assert invite_page in client.get(page).content.decode()
    answer = client.post(invite_page, {"email": ""})
    accept(shown_link(answer.content.decode()), "dee")
    assert invite_page not in client.get(page).content.decode()  # has a login now
    client.force_login(world.outsider)
    assert client.get(invite_page).status_code == 404


def test_admin_sends_a_one_time_password_link(world):
    client = team_client(world)
    answer = client.post(f"/accounts/team/{world.therapist.public_id}/password-link/")
    url = shown_link(answer.content.decode())
    assert url.startswith("/accounts/new-password/")
    visitor = Client()
    assert visitor.get(url).status_code == 200
    done = visitor.post(url, {"password1": NEW_PASSWORD, "password2": NEW_PASSWORD})
    assert done.status_code == 302 and "Welcome" in visitor.get("/").content.decode()
    assert Client().login(username="therapist", password=NEW_PASSWORD)
    assert not Client().login(username="therapist", password=PASSWORD)
    assert visitor.get(url).status_code == 410
    events = AuditEvent.objects.filter(object_type="User", action="update").order_by("at", "id")
    assert [e.username for e in events] == ["clinic-admin", "therapist"]  # made, then used
    assert {e.object_id for e in events} == {str(world.therapist.pk)}


def test_password_links_only_for_the_admins_own_clinic(world):
    client = team_client(world)
    elsewhere = f"/accounts/team/{world.outsider.public_id}/password-link/"
    assert client.post(elsewhere).status_code == 404
    api = api_as(world.clinic_admin)
    answer = api.post(f"/api/v1/users/{world.colleague.public_id}/password-link/")
    assert answer.status_code == 201 and answer.json()["url"].startswith("/accounts/new-password/")
    assert (
        api_as(world.therapist)
        .post(f"/api/v1/users/{world.colleague.public_id}/password-link/")
        .status_code
        == 403
    )


def test_a_withdrawn_link_answers_410(world):
    body = invite(world.clinic_admin, role="therapist").json()
    client = team_client(world)
    assert "Withdraw" in client.get("/accounts/team/").content.decode()
    client.post(f"/accounts/team/links/{body['id']}/withdraw/")
    assert Client().get(body["url"]).status_code == 410
