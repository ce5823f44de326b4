"""The clinic's accounts (issue 23, item 1): listed for its admin; deactivated and reactivated
through the API and the team page, a deactivated user's token answering 401 and their browser
session logged out at once; audited."""

from __future__ import annotations

import uuid

import pytest
from django.test import Client
from rest_framework.test import APIClient

from tests.personas import PASSWORD
from webapp.accounts.models import ApiToken, User
from webapp.accounts.tokens import issue_token
from webapp.audit.models import AuditEvent


def api_as(user: User) -> APIClient:
    client = APIClient()
    client.force_authenticate(user)
    return client


def api_with(key: str) -> APIClient:
    client = APIClient()
    client.credentials(HTTP_AUTHORIZATION=f"Token {key}")
    return client


def test_accounts_are_named_by_random_ids(world):
    ids = {user.public_id for user in User.objects.all()}
    assert len(ids) == User.objects.count() and all(i.version == 4 for i in ids)


def test_admin_lists_the_clinics_accounts(world):
    answer = api_as(world.clinic_admin).get("/api/v1/users/")
    assert answer.status_code == 200
    rows = {row["username"]: row for row in answer.json()["results"]}
    assert set(rows) == {"therapist", "colleague", "patient", "other-patient", "clinic-admin"}
    assert set(rows["patient"]) == {"id", "username", "role", "active", "patient"}
    assert rows["patient"] == {
        "id": str(world.patient_user.public_id),
        "username": "patient",
        "role": "patient",
        "active": True,
        "patient": str(world.patient.pk),
    }
    assert (rows["therapist"]["role"], rows["therapist"]["patient"]) == ("therapist", None)
    assert rows["clinic-admin"]["role"] == "admin"


@pytest.mark.parametrize("who", ["therapist", "patient_user", "outsider"])
def test_only_the_admin_lists_accounts(world, who):
    assert api_as(getattr(world, who)).get("/api/v1/users/").status_code == 403
    assert APIClient().get("/api/v1/users/").status_code == 401


def test_a_deactivated_users_token_answers_401_at_once(world):
    _, key = issue_token(world.therapist, "billing system")
    assert api_with(key).get("/api/v1/patients/").status_code == 200
    admin = api_as(world.clinic_admin)
    answer = admin.post(f"/api/v1/users/{world.therapist.public_id}/deactivate/")
    assert answer.status_code == 200 and answer.json()["active"] is False
    assert api_with(key).get("/api/v1/patients/").status_code == 401
    token_answer = APIClient().post(
        "/api/v1/auth/token/", {"username": "therapist", "password": PASSWORD}
    )
    assert token_answer.status_code == 400  # no new token either

    back = admin.post(f"/api/v1/users/{world.therapist.public_id}/reactivate/")
    assert back.status_code == 200 and back.json()["active"] is True
    assert api_with(key).get("/api/v1/patients/").status_code == 401  # revoked for good
    assert ApiToken.objects.get(user=world.therapist).revoked_at is not None
    _, new_key = issue_token(world.therapist, "billing system")
    assert api_with(new_key).get("/api/v1/patients/").status_code == 200


def test_a_deactivated_users_session_is_logged_out_on_the_next_page(world):
    browser = Client()
    login = browser.post("/accounts/login/", {"username": "therapist", "password": PASSWORD})
    assert login.status_code == 302
    assert browser.get("/patients/").status_code == 200
    admin = Client()
    admin.force_login(world.clinic_admin)
    admin.post(f"/accounts/team/{world.therapist.public_id}/deactivate/")
    page = browser.get("/patients/")
    assert page.status_code == 302 and page["Location"].startswith("/accounts/login/")
    assert browser.get("/api/v1/patients/").status_code == 401  # the session no longer counts
    assert not Client().login(username="therapist", password=PASSWORD)
    admin.post(f"/accounts/team/{world.therapist.public_id}/reactivate/")
    assert Client().login(username="therapist", password=PASSWORD)


def test_deactivation_and_reactivation_are_audited(world):
    admin = api_as(world.clinic_admin)
    admin.post(f"/api/v1/users/{world.patient_user.public_id}/deactivate/")
    admin.post(f"/api/v1/users/{world.patient_user.public_id}/reactivate/")
    events = AuditEvent.objects.filter(object_type="User").order_by("at", "id")
    assert [e.action for e in events] == ["update", "update"]
    assert {e.object_id for e in events} == {str(world.patient_user.pk)}
    assert {e.patient_id for e in events} == {world.patient.pk}
    assert [e.path.rsplit("/", 2)[1] for e in events] == ["deactivate", "reactivate"]


@pytest.mark.parametrize(
    ("who", "target", "status"),
    [
        ("clinic_admin", "outsider", 404),  # another clinic's account
        ("clinic_admin", "nobody", 404),
        ("clinic_admin", "not-an-id", 404),
        ("clinic_admin", "clinic_admin", 400),  # not yourself
        ("therapist", "colleague", 403),
        ("patient_user", "colleague", 403),
    ],
)
def test_who_may_deactivate_whom(world, who, target, status):
    ids = {"nobody": uuid.uuid4(), "not-an-id": "12"}
    pk = ids.get(target) or getattr(world, target).public_id
    answer = api_as(getattr(world, who)).post(f"/api/v1/users/{pk}/deactivate/")
    assert answer.status_code == status, answer.content
    assert User.objects.filter(is_active=False).count() == 0


def test_team_page_lists_accounts_with_their_state(world):
    client = Client()
    client.force_login(world.clinic_admin)
    client.post(f"/accounts/team/{world.colleague.public_id}/deactivate/")
    html = client.get("/accounts/team/").content.decode()
    row = html.split('data-username="colleague"', 1)[1].split("</tr>", 1)[0]
    assert "deactivated" in row and "Reactivate" in row
    assert "outsider" not in html  # another clinic's account
    assert client.post(f"/accounts/team/{world.outsider.public_id}/deactivate/").status_code == 404
    world.outsider.refresh_from_db()
    assert world.outsider.is_active


def test_the_schema_describes_the_account_endpoints(world):
    schema = api_as(world.therapist).get("/api/schema/?format=json").json()
    paths = schema["paths"]
    assert "post" in paths["/api/v1/invitations/"]
    assert "get" in paths["/api/v1/users/"]
    for action in ("deactivate", "reactivate", "password-link"):
        operation = paths[f"/api/v1/users/{{id}}/{action}/"]["post"]
        assert operation["parameters"][0]["schema"] == {"type": "string", "format": "uuid"}
    created = paths["/api/v1/invitations/"]["post"]["responses"]["201"]
    ref = created["content"]["application/json"]["schema"]["$ref"].rsplit("/", 1)[1]
    assert set(schema["components"]["schemas"][ref]["properties"]) == {"id", "url", "expires_at"}
