"""Issue 34 item 4: every object of the served OpenAPI schema is closed, and every answer the
test suite's API client receives is checked against it (tests/webapp/conftest.py, as zulip
checks each test response against its OpenAPI document), "does not fit" results included."""

from __future__ import annotations

import json

import pytest
from django.http import HttpResponse
from rest_framework.test import APIClient

from tests.personas import make_exercise, make_recording
from tests.webapp.openapi_check import SchemaMismatchError, check_response
from webapp.api.schema import open_objects
from webapp.api.serializers import PatientSerializer
from workers.analysis_task import analyse_run


@pytest.fixture
def api(world) -> APIClient:
    client = APIClient()
    client.force_authenticate(world.therapist)
    return client


@pytest.fixture
def analysed(world):
    """A squat analysed as a squat, and a shoulder abduction analysed as a squat (does not fit)."""
    squat = make_exercise(world.clinic, "Deep squat", "reps/m01_s01_e01.bvh.gz")
    fits = make_recording(world.patient, squat, source="reps/m01_s01_e02.bvh.gz")
    other = make_recording(world.patient, squat, source="reps/m07_s01_e02.bvh.gz")
    for recording in (fits, other):
        assert analyse_run(str(recording.runs.get().pk)) == "succeeded"
    return fits, other


def test_the_served_schema_has_no_open_object(api):
    schema = api.get("/api/schema/?format=json").json()
    assert len(schema["components"]["schemas"]) >= 60
    assert open_objects(schema) == []
    # a typed map (values by name) is not open; an object that takes any key is
    assert open_objects({"type": "object", "additionalProperties": {"type": "number"}}) == []
    assert open_objects({"properties": {"a": {"type": "object"}}}) == ["/", "/properties/a"]


def test_score_is_nullable_in_every_schema_that_carries_it(api):
    components = api.get("/api/schema/?format=json").json()["components"]["schemas"]
    carriers = {
        name: s["properties"]["score"]
        for name, s in components.items()
        if "score" in s.get("properties", {})
    }
    assert {"AnalysisResult", "AnalysisResultRepetitionResult", "RecordingSummary"} <= set(carriers)
    for name, score in carriers.items():
        assert score.get("nullable") is True, name


def test_every_answer_about_both_results_fits_the_schema(api, world, analysed):
    """Each call below goes through the hook; a mismatch would raise inside `api.get`."""
    fits, other = analysed
    for recording in (fits, other):
        detail = api.get(f"/api/v1/recordings/{recording.pk}/")
        assert detail.status_code == 200
        result = api.get(f"/api/v1/recordings/{recording.pk}/result/")
        assert result.status_code == 200 and result.json()["status"] == "succeeded"
    assert api.get(f"/api/v1/recordings/{other.pk}/").json()["result"]["score"] is None
    assert api.get(f"/api/v1/recordings/{fits.pk}/").json()["result"]["repetitions"]
    listed = api.get(f"/api/v1/patients/{world.patient.pk}/recordings/?fields=result")
    assert {r["id"] for r in listed.json()["results"]} == {str(fits.pk), str(other.pk)}
    assert api.get(f"/api/v1/patients/{world.patient.pk}/recordings/").status_code == 200
    assert api.get(f"/api/v1/patients/{world.patient.pk}/fhir/").status_code == 200
    assert api.get(f"/api/v1/patients/{world.patient.pk}/progress/").status_code == 200


def test_an_answer_with_an_undeclared_key_fails_the_hook(api, world, monkeypatch):
    assert api.get(f"/api/v1/patients/{world.patient.pk}/").status_code == 200
    written = PatientSerializer.to_representation
    monkeypatch.setattr(
        PatientSerializer,
        "to_representation",
        lambda self, patient: {**written(self, patient), "nickname": "undeclared"},
    )
    with pytest.raises(SchemaMismatchError, match="nickname"):
        api.get(f"/api/v1/patients/{world.patient.pk}/")


def fake(status: int, body, content_type: str = "application/json") -> HttpResponse:
    return HttpResponse(json.dumps(body), status=status, content_type=content_type)


def test_the_hook_refuses_what_the_schema_does_not_say():
    path = "/api/v1/patients/8f2ab1c0-0000-4000-8000-000000000000/"
    good = {
        "id": "8f2ab1c0-0000-4000-8000-000000000000",
        "display_name": "A",
        "date_of_birth": None,
        "created_at": "2026-11-28T10:00:00Z",
        "archived_at": None,
        "last_activity_at": None,
    }
    check_response("GET", path, fake(200, good))  # fits
    check_response("GET", "/accounts/login/", fake(500, "anything"))  # not the API
    wrong = [
        (fake(200, {**good, "nickname": "x"}), "nickname"),  # a key the schema does not name
        (fake(200, {k: v for k, v in good.items() if k != "id"}), "'id' is a required"),
        (fake(418, {"detail": "teapot"}), "status not documented"),
        (fake(200, good, "text/html"), "not documented"),
        (fake(404, {"detail": {"nested": 3}}), "does not fit"),
    ]
    for response, said in wrong:
        with pytest.raises(SchemaMismatchError, match=said):
            check_response("GET", path, response)
