"""Every page and API endpoint × every persona, with the status each must get.

Objects of another clinic (or another patient's) answer 404 so their existence is not revealed;
actions a role may not take answer 403; anonymous visitors are sent to the login page (pages) or
get 401 (API).
"""

from __future__ import annotations

from dataclasses import dataclass

import pytest
from django.urls import reverse

from tests.personas import make_exercise, make_recording

PERSONAS = ("therapist", "colleague", "outsider", "patient", "other_patient", "anonymous")


@dataclass(frozen=True)
class Case:
    name: str
    target: str | None  # which object's pk the URL takes
    method: str
    expected: tuple[int, int, int, int, int, int]  # in PERSONAS order


STAFF_ONLY_OBJECT = (200, 200, 404, 403, 403, 302)
OWN_OBJECT = (200, 200, 404, 200, 404, 302)
OWN_API_OBJECT = (200, 200, 404, 200, 404, 401)

CASES = [
    Case("dashboard:home", None, "get", (200, 200, 200, 200, 200, 302)),
    Case("patients:list", None, "get", (200, 200, 200, 403, 403, 302)),
    Case("patients:create", None, "get", (200, 200, 200, 403, 403, 302)),
    Case("patients:detail", "patient", "get", OWN_OBJECT),
    Case("patients:edit", "patient", "get", STAFF_ONLY_OBJECT),
    Case("patients:prescribe", "patient", "get", STAFF_ONLY_OBJECT),
    Case("patients:archive", "patient", "post", (302, 302, 404, 403, 403, 302)),
    Case("patients:progress", "patient", "get", OWN_OBJECT),
    Case("patients:history-csv", "patient", "get", OWN_OBJECT),
    Case("exercises:list", None, "get", (200, 200, 200, 403, 403, 302)),
    Case("exercises:create", None, "get", (200, 200, 200, 403, 403, 302)),
    Case("exercises:detail", "exercise", "get", STAFF_ONLY_OBJECT),
    Case("exercises:model-status", "exercise", "get", STAFF_ONLY_OBJECT),
    Case("exercises:tutor-data", "exercise", "get", STAFF_ONLY_OBJECT),
    Case("exercises:annotate", "exercise", "get", STAFF_ONLY_OBJECT),
    # Empty POSTs: staff get the validation answer (400), others 403/404/login.
    Case("exercises:landmarks", "exercise", "post", (400, 400, 404, 403, 403, 302)),
    Case("exercises:grammar", "exercise", "post", (400, 400, 404, 403, 403, 302)),
    Case("exercises:build", "exercise", "post", (302, 302, 404, 403, 403, 302)),
    Case("recordings:upload", None, "get", (200, 200, 200, 200, 200, 302)),
    Case("recordings:detail", "recording", "get", OWN_OBJECT),
    Case("recordings:status", "recording", "get", OWN_OBJECT),
    Case("recordings:rerun", "recording", "post", (302, 302, 404, 403, 403, 302)),
    Case("recordings:result", "recording", "get", OWN_OBJECT),
    Case("recordings:corrections", "recording", "get", STAFF_ONLY_OBJECT),
    # The recording's exercise is set, so confirming redirects to the recording.
    Case("recordings:confirm", "recording", "get", (302, 302, 404, 302, 404, 302)),
    Case("api-patients", None, "get", (200, 200, 200, 200, 200, 401)),
    Case("api-patient", "patient", "get", OWN_API_OBJECT),
    Case("api-patient-recordings", "patient", "get", OWN_API_OBJECT),
    Case("api-patient-progress", "patient", "get", OWN_API_OBJECT),
    Case("api-patient-prescriptions", "patient", "get", OWN_API_OBJECT),
    Case("api-exercises", None, "get", (200, 200, 200, 200, 200, 401)),
    Case("api-recording", "recording", "get", OWN_API_OBJECT),
    Case("api-recording-result", "recording", "get", OWN_API_OBJECT),
    Case("api-recording-corrections", "recording", "get", (200, 200, 404, 403, 404, 401)),
    Case("api-recording-confirm", "recording", "post", (400, 400, 404, 400, 404, 401)),
    Case("api-schema", None, "get", (200, 200, 200, 200, 200, 401)),
    Case("reports:playback", "recording", "get", OWN_OBJECT),
    Case("reports:playback-bin", "recording", "get", (409, 409, 404, 409, 404, 302)),
    Case("reports:recording-pdf", "recording", "get", (202, 202, 404, 202, 404, 302)),
    Case("reports:recording-print", "recording", "get", OWN_OBJECT),
    Case("reports:progress", "patient", "get", OWN_OBJECT),
    Case("reports:progress-pdf", "patient", "get", (202, 202, 404, 202, 404, 302)),
    Case("reports:progress-print", "patient", "get", OWN_OBJECT),
    Case("reports:api-recording-report", "recording", "get", (202, 202, 404, 202, 404, 401)),
    Case("reports:api-progress-report", "patient", "get", (202, 202, 404, 202, 404, 401)),
]


@pytest.fixture
def objects(world):
    exercise = make_exercise(world.clinic)
    recording = make_recording(world.patient, exercise)
    return {"patient": world.patient, "exercise": exercise, "recording": recording}


def log_in(client, world, persona: str) -> None:
    users = {
        "therapist": world.therapist,
        "colleague": world.colleague,
        "outsider": world.outsider,
        "patient": world.patient_user,
        "other_patient": world.other_patient_user,
    }
    if persona in users:
        client.force_login(users[persona])


@pytest.mark.parametrize("persona", PERSONAS)
@pytest.mark.parametrize("case", CASES, ids=lambda case: case.name)
def test_access(client, world, objects, case: Case, persona: str):
    kwargs = {"pk": objects[case.target].pk} if case.target else {}
    url = reverse(case.name, kwargs=kwargs)
    log_in(client, world, persona)
    response = getattr(client, case.method)(url)
    expected = case.expected[PERSONAS.index(persona)]
    assert response.status_code == expected, f"{persona} {case.method.upper()} {url}"


def test_matrix_covers_every_named_route():
    from django.urls import get_resolver

    covered = {case.name for case in CASES}
    exempt = {
        "healthz",
        "api-token",
        "api-docs",
        "api-recordings",
        "accounts",
        "admin",
    }
    names = set()
    for pattern in get_resolver().url_patterns:
        for sub in getattr(pattern, "url_patterns", [pattern]):
            namespace = getattr(pattern, "namespace", None)
            if getattr(sub, "name", None) and namespace not in {"admin", "accounts"}:
                names.add(f"{namespace}:{sub.name}" if namespace else sub.name)
    missing = sorted(names - covered - exempt)
    assert missing == []
