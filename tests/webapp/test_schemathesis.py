"""Schemathesis against the API's own OpenAPI schema (`/api/schema/`, drf-spectacular), as a
therapist with an API token: no answer is a 5xx and every answer conforms to the schema (status
code, content type, body, headers).

The schema is read through the Django WSGI application, and so are the generated calls; the
database is the test database, holding one clinic with a patient, an exercise and a recording, so
that path parameters name real objects about half the time (random ones answer 404).
``SCHEMATHESIS_EXAMPLES`` (default 25) is the number of generated calls per operation.
"""

from __future__ import annotations

import os
from collections import Counter
from contextlib import contextmanager

import pytest
import schemathesis
from django.core.signals import request_finished, request_started
from django.core.wsgi import get_wsgi_application
from django.db import close_old_connections
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rest_framework.test import APIClient
from schemathesis.specs.openapi.checks import positive_data_acceptance

from analysis.bvh import read
from analysis.pipeline import analyse, build_model
from tests.personas import FIXTURES, PASSWORD, fixture_landmarks, make_exercise, make_recording
from webapp.recordings.models import AnalysisRun, RunStatus

EXAMPLES = int(os.environ.get("SCHEMATHESIS_EXAMPLES", "25"))
# The token endpoint takes passwords: fuzzing it would lock the test client out (django-axes),
# and its answers are covered by the accounts tests.
SKIPPED_PATHS = ("/api/v1/auth/token/",)
# "Schema-valid data is accepted" cannot hold where validity is more than the schema can say: an
# upload must be a readable BVH of the exercise's rig, a confirmation needs a recording without
# exercise, a correction a finished analysis, a move an exercise or patient of the clinic. Those
# answer 400 with the reason; the other checks (no 5xx, documented status, content type, body and
# headers) still apply to them.
SEMANTIC_BODIES = ("POST", "PATCH")


@contextmanager
def connection_kept_open():
    """A real request closes the database connection when it starts and ends
    (`close_old_connections`), which on PostgreSQL ends the test's transaction; Django's own test
    client detaches it the same way, and reattaches it after each of its requests, so this wraps
    only the WSGI calls."""
    signals = (request_started, request_finished)
    for signal in signals:
        signal.disconnect(close_old_connections)
    try:
        yield
    finally:
        for signal in signals:
            signal.connect(close_old_connections)


@pytest.fixture
def token(world) -> str:
    answer = APIClient().post(
        "/api/v1/auth/token/", {"username": world.therapist.username, "password": PASSWORD}
    )
    assert answer.status_code == 200, answer.content
    return answer.json()["token"]


# The clinic's accounts are its admin's to manage: these operations are called with the admin's
# token, after all the others (a generated id may switch off the therapist's account).
ADMIN_PATHS = ("/api/v1/users/",)


@pytest.fixture
def admin_token(world) -> str:
    answer = APIClient().post(
        "/api/v1/auth/token/", {"username": world.clinic_admin.username, "password": PASSWORD}
    )
    assert answer.status_code == 200, answer.content
    return answer.json()["token"]


@pytest.fixture
def real_ids(world) -> dict[str, str]:
    exercise = make_exercise(world.clinic)
    recording = make_recording(world.patient, exercise)
    analysed(recording)  # its answers carry a real result, checked against the closed schema
    # DELETE names a recording of its own: the reads that follow still reach `recording`.
    spare = make_recording(world.patient, exercise, source="reps/m01_s01_e03.bvh.gz")
    ids = {"patient": world.patient.pk, "recording": recording.pk, "spare": spare.pk}
    ids["user"] = world.colleague.pk  # an account the admin may switch off and on
    return {kind: str(pk) for kind, pk in ids.items()}


def analysed(recording) -> None:
    """The recording's run succeeded with the pipeline's result (cold-start model of the tutor)."""
    tutor = "reps/m01_s01_e01.bvh.gz"
    model = build_model(read(FIXTURES / tutor), *fixture_landmarks(tutor))
    summary = analyse(read(FIXTURES / "reps/m01_s01_e02.bvh.gz"), model).to_json()
    AnalysisRun.objects.filter(recording=recording).update(
        status=RunStatus.SUCCEEDED, progress=100, summary=summary, score=summary["score"]
    )


def with_real_ids(case, real_ids: dict[str, str]):
    """Point the case's object id ({id} in the schema) at an object of the therapist's clinic."""
    for name in case.path_parameters or {}:
        kind = "patient" if "/patients/" in case.operation.path else "recording"
        kind = "spare" if case.method.upper() == "DELETE" else kind
        kind = "user" if "/users/" in case.operation.path else kind
        case.path_parameters[name] = real_ids[kind]
    return case


def operations(schema):
    for result in schema.get_all_operations():
        operation = result.ok()
        if operation.path not in SKIPPED_PATHS:
            yield operation


class Tally:
    def __init__(self) -> None:
        self.calls: Counter[str] = Counter()
        self.statuses: Counter[str] = Counter()
        self.failures: Counter[str] = Counter()


def exercise_operation(operation, auth: dict, real_ids: dict, tally: Tally) -> None:
    """EXAMPLES generated calls of one operation; failures are counted, not raised, so one run
    lists every operation's problems."""
    label = operation.label
    excluded = [positive_data_acceptance] if operation.method.upper() in SEMANTIC_BODIES else []
    generated = operation.as_strategy()
    pointed = generated.map(lambda case: with_real_ids(case, real_ids))

    @settings(
        max_examples=EXAMPLES,
        derandomize=True,
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
    )
    @given(case=st.one_of(generated, pointed))
    def call(case):
        tally.calls[label] += 1
        try:
            response = case.call_and_validate(headers=auth, excluded_checks=excluded)
        except (AssertionError, BaseExceptionGroup) as error:  # schemathesis' failed checks
            tally.failures[f"{label}: {' '.join(str(error).split())[:300]}"] += 1
            return
        tally.statuses[f"{label} -> {response.status_code}"] += 1

    call()


def test_api_answers_conform_to_its_schema(token, admin_token, real_ids, monkeypatch):
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda run_id: None)
    auth = {"Authorization": f"Token {token}"}
    tally = Tally()
    with connection_kept_open():
        app = get_wsgi_application()
        schema = schemathesis.openapi.from_wsgi("/api/schema/?format=json", app, headers=auth)
        admin_auth = {"Authorization": f"Token {admin_token}"}
        for operation in sorted(operations(schema), key=lambda o: o.path.startswith(ADMIN_PATHS)):
            by_admin = operation.path.startswith(ADMIN_PATHS)
            exercise_operation(operation, admin_auth if by_admin else auth, real_ids, tally)

    print(f"\nschemathesis: {sum(tally.calls.values())} calls over {len(tally.calls)} operations")
    for line, count in sorted(tally.statuses.items()):
        print(f"  {line}: {count}")
    for line, count in sorted(tally.failures.items()):
        print(f"  FAILED {count}x {line}")
    assert len(tally.calls) >= 10, tally.calls  # every documented operation was exercised
    answered = {line.rsplit(" -> ", 1)[0] for line in tally.statuses if " -> 2" in line}
    reads = {label for label in tally.calls if label.startswith("GET ")}
    assert reads <= answered, reads - answered  # each read also reached a real object
    assert not tally.failures, tally.failures
