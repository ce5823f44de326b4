"""Every page and API endpoint × every persona, with the status each must get.

Objects of another clinic (or another patient's) answer 404 so their existence is not revealed;
actions a role may not take answer 403; anonymous visitors are sent to the login page (pages) or
get 401 (API). The routes come from the URL resolver: a route without a row here fails
`test_matrix_covers_every_route`, and Django's admin site is checked route by route.
"""

from __future__ import annotations

import datetime
import re
from dataclasses import dataclass

import pytest
from django.test import Client
from django.urls import URLPattern, URLResolver, get_resolver, reverse

from tests.personas import make_exercise, make_recording
from webapp.accounts.tokens import issue_token
from webapp.live.models import LiveSession
from webapp.patients.models import Prescription

PERSONAS = (
    "therapist",
    "colleague",
    "clinic_admin",
    "outsider",
    "patient",
    "other_patient",
    "anonymous",
)
Statuses = tuple[int, int, int, int, int, int, int]  # in PERSONAS order


@dataclass(frozen=True)
class Case:
    name: str
    target: str | None  # which object the URL names (see `url_kwargs`)
    method: str
    expected: Statuses


EVERYONE_200: Statuses = (200, 200, 200, 200, 200, 200, 200)
STAFF_PAGE: Statuses = (200, 200, 200, 200, 403, 403, 302)
SIGNED_IN_PAGE: Statuses = (200, 200, 200, 200, 200, 200, 302)
STAFF_ONLY_OBJECT: Statuses = (200, 200, 200, 404, 403, 403, 302)
OWN_OBJECT: Statuses = (200, 200, 200, 404, 200, 404, 302)
# The patient's own copy of a therapist page is sent to the patient's pages (302), in lay words.
OWN_OBJECT_PATIENT_ELSEWHERE: Statuses = (200, 200, 200, 404, 302, 404, 302)
OWN_API_OBJECT: Statuses = (200, 200, 200, 404, 200, 404, 401)
OWN_REPORT_PDF: Statuses = (202, 202, 202, 404, 202, 404, 302)
OWN_API_REPORT: Statuses = (202, 202, 202, 404, 202, 404, 401)
ADMIN_ONLY_PAGE: Statuses = (403, 403, 200, 403, 403, 403, 302)
ADMIN_ONLY_ACTION: Statuses = (403, 403, 302, 403, 403, 403, 302)
ADMIN_ONLY_API: Statuses = (403, 403, 200, 403, 403, 403, 401)

CASES = [
    Case("healthz", None, "get", EVERYONE_200),
    # The favicon redirects to the static SVG; the guide and its pictures are public help.
    Case("favicon", None, "get", (302, 302, 302, 302, 302, 302, 302)),
    Case("help:guide", None, "get", EVERYONE_200),
    Case("help:image", "guide-image", "get", EVERYONE_200),
    # Accounts. A signed-in visitor of the login page is sent on to the dashboard.
    Case("accounts:login", None, "get", (302, 302, 302, 302, 302, 302, 200)),
    Case("accounts:logout", None, "post", (302, 302, 302, 302, 302, 302, 302)),
    Case("accounts:password-change", None, "get", SIGNED_IN_PAGE),
    Case("accounts:password-changed", None, "get", SIGNED_IN_PAGE),
    Case("accounts:password-reset", None, "get", EVERYONE_200),
    Case("accounts:password-reset-sent", None, "get", EVERYONE_200),
    # A forged reset link shows the "invalid link" page (200) and changes nothing.
    Case("accounts:password-reset-confirm", "reset", "get", EVERYONE_200),
    Case("accounts:password-reset-complete", None, "get", EVERYONE_200),
    Case("accounts:2fa-setup", None, "get", STAFF_PAGE),
    Case("accounts:2fa-verify", None, "get", SIGNED_IN_PAGE),
    Case("accounts:tokens", None, "get", STAFF_PAGE),
    # The therapist's token: they and the clinic admin may revoke it, a colleague cannot see it.
    Case("accounts:token-revoke", "token", "post", (302, 404, 302, 404, 403, 403, 302)),
    Case("audit:events", None, "get", (403, 403, 200, 403, 403, 403, 302)),
    Case("audit:export", None, "get", ADMIN_ONLY_PAGE),
    # The team page and its actions are the clinic admin's (the account named is the colleague);
    # the therapist invites their own patient from the patient page, not a colleague's.
    Case("accounts:team", None, "get", ADMIN_ONLY_PAGE),
    Case("accounts:team-deactivate", "account", "post", ADMIN_ONLY_ACTION),
    Case("accounts:team-reactivate", "account", "post", ADMIN_ONLY_ACTION),
    Case("accounts:team-password-link", "account", "post", ADMIN_ONLY_PAGE),
    Case("accounts:team-withdraw-link", "link", "post", ADMIN_ONLY_ACTION),
    Case("accounts:invite-patient", "patient", "get", (200, 403, 200, 404, 403, 403, 302)),
    # A one-time link's page opens for anyone holding the link (opening it spends nothing).
    Case("accounts:invitation", "invitation-link", "get", EVERYONE_200),
    Case("accounts:new-password", "password-link", "get", EVERYONE_200),
    Case("dashboard:home", None, "get", SIGNED_IN_PAGE),
    # The camera page: the patient's own prescription, or one of the clinic's for the staff; the
    # exercise here has no model yet, so starting a session answers 409 to those who may.
    Case("camera:page", "prescription", "get", OWN_OBJECT),
    Case("camera:start", "prescription", "post", (409, 409, 409, 404, 409, 404, 302)),
    # The patient's own pages: staff have their own; an exercise not prescribed to them is 404.
    Case("dashboard:my-progress", None, "get", (403, 403, 403, 403, 200, 200, 302)),
    # prescribed to the patient (the camera rows need the prescription): theirs to watch
    Case("dashboard:my-reference", "exercise", "get", (403, 403, 403, 403, 200, 404, 302)),
    Case("dashboard:my-effort", "recording", "post", (403, 403, 403, 403, 400, 404, 302)),
    Case("patients:list", None, "get", STAFF_PAGE),
    Case("patients:create", None, "get", STAFF_PAGE),
    Case("patients:detail", "patient", "get", OWN_OBJECT_PATIENT_ELSEWHERE),
    Case("patients:edit", "patient", "get", STAFF_ONLY_OBJECT),
    Case("patients:prescribe", "patient", "get", STAFF_ONLY_OBJECT),
    Case("patients:archive", "patient", "post", (302, 302, 302, 404, 403, 403, 302)),
    Case("patients:progress", "patient", "get", OWN_OBJECT),
    Case("patients:history-csv", "patient", "get", OWN_OBJECT),
    Case("patients:compare", "patient", "get", OWN_OBJECT),
    Case("exercises:list", None, "get", STAFF_PAGE),
    Case("exercises:create", None, "get", STAFF_PAGE),
    Case("exercises:detail", "exercise", "get", STAFF_ONLY_OBJECT),
    Case("exercises:model-status", "exercise", "get", STAFF_ONLY_OBJECT),
    Case("exercises:tutor-data", "exercise", "get", STAFF_ONLY_OBJECT),
    Case("exercises:annotate", "exercise", "get", STAFF_ONLY_OBJECT),
    # Empty POSTs: staff get the validation answer (400), others 403/404/login.
    Case("exercises:landmarks", "exercise", "post", (400, 400, 400, 404, 403, 403, 302)),
    Case("exercises:grammar", "exercise", "post", (400, 400, 400, 404, 403, 403, 302)),
    Case("exercises:build", "exercise", "post", (302, 302, 302, 404, 403, 403, 302)),
    Case("exercises:edit", "exercise", "get", STAFF_ONLY_OBJECT),
    Case("exercises:archive", "exercise", "get", STAFF_ONLY_OBJECT),
    Case("exercises:reference", "exercise", "get", STAFF_ONLY_OBJECT),
    Case("exercises:reference-data", "exercise", "get", STAFF_ONLY_OBJECT),
    Case("exercises:add-rule", "exercise", "post", (400, 400, 400, 404, 403, 403, 302)),
    Case("recordings:upload", None, "get", SIGNED_IN_PAGE),
    Case("recordings:detail", "recording", "get", OWN_OBJECT),
    Case("recordings:status", "recording", "get", OWN_OBJECT),
    Case("recordings:rerun", "recording", "post", (302, 302, 302, 404, 403, 403, 302)),
    Case("recordings:label", "recording", "post", (302, 302, 302, 404, 403, 403, 302)),
    Case("recordings:result", "recording", "get", OWN_OBJECT),
    # a phone video's frames: the world's recording is a BVH file, so there is none to see
    Case("recordings:video", "recording", "get", (404, 404, 404, 404, 404, 404, 302)),
    Case("recordings:corrections", "recording", "get", STAFF_ONLY_OBJECT),
    # The recording's exercise is set, so confirming redirects to the recording.
    Case("recordings:confirm", "recording", "get", (302, 302, 302, 404, 302, 404, 302)),
    # Moving and deleting (the form, the confirmation page) are for staff; the deleted list and
    # restoring for the clinic admin, who gets 404 for a recording that is not deleted.
    Case("recordings:move", "recording", "get", STAFF_ONLY_OBJECT),
    Case("recordings:delete", "recording", "get", STAFF_ONLY_OBJECT),
    Case("recordings:deleted", None, "get", (403, 403, 200, 403, 403, 403, 302)),
    Case("recordings:restore", "recording", "post", (403, 403, 404, 403, 403, 403, 302)),
    # The token endpoint takes no session; an empty form is a 400 for everyone.
    Case("api-token", None, "post", (400, 400, 400, 400, 400, 400, 400)),
    Case("api-patients", None, "get", (200, 200, 200, 200, 200, 200, 401)),
    Case("api-patient", "patient", "get", OWN_API_OBJECT),
    Case("api-patient-recordings", "patient", "get", OWN_API_OBJECT),
    Case("api-patient-progress", "patient", "get", OWN_API_OBJECT),
    Case("api-patient-prescriptions", "patient", "get", OWN_API_OBJECT),
    Case("api-patient-history-csv", "patient", "get", OWN_API_OBJECT),
    Case("api-patient-fhir", "patient", "get", OWN_API_OBJECT),
    Case("api-exercises", None, "get", (200, 200, 200, 200, 200, 200, 401)),
    # An empty upload names no patient: 400 for anyone signed in.
    Case("api-recordings", None, "post", (400, 400, 400, 400, 400, 400, 401)),
    Case("api-recording", "recording", "get", OWN_API_OBJECT),
    Case("api-recording-result", "recording", "get", OWN_API_OBJECT),
    Case("api-recording-corrections", "recording", "get", (200, 200, 200, 404, 403, 404, 401)),
    Case("api-recording-confirm", "recording", "post", (400, 400, 400, 404, 400, 404, 401)),
    Case("api-schema", None, "get", (200, 200, 200, 200, 200, 200, 401)),
    # The Swagger page asks for the sign-in its schema request (api-schema) needs.
    Case("api-docs", None, "get", SIGNED_IN_PAGE),
    Case("reports:playback", "recording", "get", OWN_OBJECT),
    Case("reports:playback-bin", "recording", "get", (409, 409, 409, 404, 409, 404, 302)),
    Case("reports:recording-pdf", "recording", "get", OWN_REPORT_PDF),
    Case("reports:recording-print", "recording", "get", OWN_OBJECT),
    Case("reports:progress", "patient", "get", OWN_OBJECT_PATIENT_ELSEWHERE),
    Case("reports:progress-pdf", "patient", "get", OWN_REPORT_PDF),
    Case("reports:progress-print", "patient", "get", OWN_OBJECT),
    Case("reports:api-recording-report", "recording", "get", OWN_API_REPORT),
    Case("reports:api-progress-report", "patient", "get", OWN_API_REPORT),
    # Live sessions: the page and its status follow the session's patient; replaying a recording
    # is open to whoever may see it; an empty POST names no patient (400).
    Case("live:page", "live", "get", OWN_OBJECT),
    Case("live:status", "live", "get", OWN_OBJECT),
    Case("live:replay", "recording", "post", (302, 302, 302, 404, 302, 404, 302)),
    # Starting (an empty form offers no exercise: back to the patient page) and watching are
    # the clinic staff's.
    Case("live:start", "patient", "post", (302, 302, 302, 404, 403, 403, 302)),
    Case("live:watch", "live", "get", STAFF_ONLY_OBJECT),
    Case("api-live-sessions", None, "post", (400, 400, 400, 400, 400, 400, 401)),
    # Accounts: an empty invitation names no role (400) for staff; patients never invite.
    Case("api-invitations", None, "post", (400, 400, 400, 400, 403, 403, 401)),
    Case("api-users", None, "get", ADMIN_ONLY_API),
    Case("api-user-deactivate", "account", "post", ADMIN_ONLY_API),
    Case("api-user-reactivate", "account", "post", ADMIN_ONLY_API),
    Case("api-user-password-link", "account", "post", (403, 403, 201, 403, 403, 403, 401)),
    # Goals and clinical notes: staff write (an empty form is refused with a message on the page
    # it returns to), the patient reads their own.
    Case("patients:add-goal", "patient", "post", (302, 302, 302, 404, 403, 403, 302)),
    Case("recordings:add-note", "recording", "post", (302, 302, 302, 404, 403, 403, 302)),
    Case("api-patient-goals", "patient", "get", OWN_API_OBJECT),
    Case("api-recording-notes", "recording", "get", OWN_API_OBJECT),
]


@pytest.fixture
def objects(world):
    exercise = make_exercise(world.clinic)
    recording = make_recording(world.patient, exercise)
    token, _ = issue_token(world.therapist, "practice system")
    live = LiveSession.objects.create(
        clinic=world.clinic, patient=world.patient, exercise=exercise, created_by=world.therapist
    )
    prescription = Prescription.objects.create(
        patient=world.patient, exercise=exercise, start_date=datetime.date(2026, 11, 2)
    )
    return {"patient": world.patient, "exercise": exercise, "recording": recording, "token": token,
            "live": live, "prescription": prescription, **account_objects(world)}  # fmt: skip


def account_objects(world) -> dict:
    """The colleague's account, a pending invitation, and the keys of two one-time links."""
    from webapp.accounts.invitations import create_invitation, create_password_link
    from webapp.accounts.models import Role

    invitation, invitation_key = create_invitation(world.clinic_admin, Role.THERAPIST)
    _, password_key = create_password_link(world.clinic_admin, world.colleague)
    return {"account": world.colleague, "link": invitation,
            "invitation-link": invitation_key, "password-link": password_key}  # fmt: skip


def url_kwargs(target: str | None, objects: dict) -> dict:
    if target is None:
        return {}
    if target == "reset":
        return {"uidb64": "MQ", "token": "forged-reset-token"}
    if target == "guide-image":
        return {"name": "guide-home.png"}
    if target == "account":
        return {"pk": objects["account"].public_id}
    if target.endswith("-link") and target != "link":
        return {"token": objects[target]}
    return {"pk": objects[target].pk}


def user_of(world, persona: str):
    return None if persona == "anonymous" else getattr(world, PERSONA_USERS[persona])


PERSONA_USERS = {
    "therapist": "therapist",
    "colleague": "colleague",
    "clinic_admin": "clinic_admin",
    "outsider": "outsider",
    "patient": "patient_user",
    "other_patient": "other_patient_user",
}


def status_for(world, persona: str, method: str, url: str) -> int:
    client = Client()
    user = user_of(world, persona)
    if user is not None:
        client.force_login(user)
    return getattr(client, method)(url).status_code


@pytest.mark.parametrize("case", CASES, ids=lambda case: case.name)
def test_access(world, objects, case: Case):
    """One route, every persona (one world per route keeps the matrix fast)."""
    url = reverse(case.name, kwargs=url_kwargs(case.target, objects))
    answers = {p: status_for(world, p, case.method, url) for p in PERSONAS}
    expected = dict(zip(PERSONAS, case.expected, strict=True))
    wrong = {
        p: f"got {answers[p]}, expected {expected[p]}"
        for p in PERSONAS
        if answers[p] != expected[p]
    }
    assert wrong == {}, f"{case.method.upper()} {url}"


def walk_routes(patterns, namespace: str | None = None, prefix: str = ""):
    """(qualified name or None, full route) of every URL pattern, through nested includes."""
    for pattern in patterns:
        if isinstance(pattern, URLResolver):
            inner = ":".join(part for part in (namespace, pattern.namespace) if part) or None
            yield from walk_routes(pattern.url_patterns, inner, prefix + str(pattern.pattern))
        elif isinstance(pattern, URLPattern):
            name = pattern.name and (f"{namespace}:{pattern.name}" if namespace else pattern.name)
            yield name, prefix + str(pattern.pattern)


def all_routes() -> list[tuple[str | None, str]]:
    return list(walk_routes(get_resolver().url_patterns))


def is_admin(route: str) -> bool:
    return route.startswith("admin/")


def test_matrix_covers_every_route():
    """Every route (pages, API, router-generated, unnamed) is in CASES or is an admin route."""
    covered = {case.name for case in CASES}
    missing = sorted(
        name or route for name, route in all_routes() if not is_admin(route) and name not in covered
    )
    assert missing == []
    assert len(covered) == len(CASES), "a route appears twice in CASES"


PARAMETER = re.compile(r"<(?:(?P<converter>\w+):)?(?P<name>\w+)>|\(\?P<(?P<group>\w+)>[^)]*\)")


def test_object_ids_in_urls_are_not_guessable():
    """Outside the staff-only admin site, objects are named by UUID (or a signed reset token).

    The guide's screenshots are public files named by their file name, not clinic objects.
    """
    weak = []
    for name, route in all_routes():
        if is_admin(route) or name == "help:image":
            continue
        for match in PARAMETER.finditer(route):
            signed = match["name"] in {"uidb64", "token"}
            if match["converter"] != "uuid" and not signed:
                weak.append(f"{name}: {match.group(0)}")
    assert weak == []


# Sample values for admin route parameters; any other parameter (ids of one model or another) is 1.
ADMIN_SAMPLES = {"app_label": "accounts", "url": "x"}


def admin_url(route: str) -> str:
    def sample(match: re.Match) -> str:
        return ADMIN_SAMPLES.get(match["name"] or match["group"], "1")

    return "/" + PARAMETER.sub(sample, route).strip("^$")


def admin_answer_is_closed(url: str, response) -> bool:
    if url == "/admin/login/":
        return response.status_code == 200  # the form; signing in needs a staff account
    if url == "/admin/logout/":
        return response.status_code in (200, 302)  # signing out is harmless
    return response.status_code == 302 and "/admin/login/" in response["Location"]


def test_admin_site_is_closed_to_every_persona(world, objects):
    """No persona is Django staff: every admin route sends each of them to the admin login."""
    # Signing out is checked last, so each persona keeps one session for all the other routes.
    urls = sorted(
        (admin_url(route) for _, route in all_routes() if is_admin(route)),
        key=lambda url: url == "/admin/logout/",
    )
    assert len(urls) > 40  # the admin of every registered model is in the walk
    wrong = []
    for persona in PERSONAS:
        client = Client()
        if (user := user_of(world, persona)) is not None:
            client.force_login(user)
        for url in urls:
            response = client.post(url) if url == "/admin/logout/" else client.get(url)
            if not admin_answer_is_closed(url, response):
                wrong.append(f"{persona} {url} → {response.status_code}")
    assert wrong == []
