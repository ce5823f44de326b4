"""One result contract from the pipeline to the API (issue 22): the API serves the typed result's
JSON, under an OpenAPI schema generated from the result dataclasses with every object closed, and
a stored result that lacks a field reads as "not stored" (None), never as an invented value."""

from __future__ import annotations

import json

import jsonschema
import pytest
from rest_framework.test import APIClient

from analysis.bvh import read
from analysis.pipeline import AnalysisSummary, analyse, build_model
from tests.personas import FIXTURES, fixture_landmarks, make_exercise, make_recording
from webapp.api.result_schema import NULL_NAME, ROOT_NAME, json_schema, result_components
from webapp.recordings.models import AnalysisRun, RunStatus
from webapp.recordings.reading import reading_of

# Three exercises of different body parts (squat, side lunge, shoulder abduction: the last one
# has a hand workspace); a correct and an incorrect recording of each.
EXERCISES = {
    "Deep squat": "m01",
    "Side lunge": "m04",
    "Shoulder abduction": "m07",
}
RECORDINGS = ("s01_e02", "s01_e03_inc")


def tutor_source(movement: str) -> str:
    return f"reps/{movement}_s01_e01.bvh.gz"


@pytest.fixture(scope="module")
def results() -> dict[tuple[str, str], dict]:
    """Each recording's typed result, as the worker stores it (JSON), by (exercise, source)."""
    out = {}
    for movement in EXERCISES.values():
        tutor = tutor_source(movement)
        model = build_model(read(FIXTURES / tutor), *fixture_landmarks(tutor))
        for take in RECORDINGS:
            source = f"reps/{movement}_{take}.bvh.gz"
            typed = analyse(read(FIXTURES / source), model).to_json()
            out[movement, source] = json.loads(json.dumps(typed))
    return out


@pytest.fixture
def api(world) -> APIClient:
    client = APIClient()
    client.force_authenticate(world.therapist)
    return client


def validator() -> jsonschema.Draft202012Validator:
    return jsonschema.Draft202012Validator(json_schema())


def test_every_result_fits_the_generated_schema(results):
    check = validator()
    workspaces = 0
    for key, result in results.items():
        errors = [f"{list(e.absolute_path)}: {e.message}" for e in check.iter_errors(result)]
        assert errors == [], (key, errors[:5])
        assert result["repetitions"], key  # the nested objects were checked too
        workspaces += bool(result["workspace"])
    assert workspaces >= 1  # the shoulder exercise measured its hands' workspace


def test_the_schema_is_closed_so_drift_fails(results):
    check = validator()
    result = next(iter(results.values()))
    assert check.is_valid(result)
    added = {**result, "a_key_nobody_declared": 1}
    assert not check.is_valid(added)
    missing = {k: v for k, v in result.items() if k != "advice"}
    assert not check.is_valid(missing)
    repetition = {**result["repetitions"][0], "gbdtw": 1.0}
    assert not check.is_valid({**result, "repetitions": [repetition]})
    wrong_type = {**result, "segmentation": 3}
    assert not check.is_valid(wrong_type)


def test_every_component_object_is_closed():
    components = result_components()
    for name, schema in components.items():
        if name == NULL_NAME:  # JSON null, for the nullable references
            assert schema["enum"] == [None] and schema["nullable"] is True
            continue
        assert schema["additionalProperties"] is False, name
        assert set(schema["required"]) <= set(schema["properties"]), name
    root = components[ROOT_NAME]["properties"]
    for key in ("advice", "workspace", "tempo", "match", "clinical_notes", "repetition_count"):
        assert key in root
    repetition = components[ROOT_NAME + "RepetitionResult"]["properties"]
    assert {"gbdtw_score", "clinical_angles", "passed", "excursion"} <= set(repetition)


def test_served_schema_holds_the_generated_components(api):
    served = api.get("/api/schema/?format=json").json()["components"]["schemas"]
    for name, schema in result_components().items():
        assert served[name] == schema, name
    result_field = served["Recording"]["properties"]["result"]
    # OpenAPI 3.0.3: `nullable` beside an allOf would still refuse null; Null allows it
    assert result_field["anyOf"] == [
        {"$ref": f"#/components/schemas/{ROOT_NAME}"},
        {"$ref": f"#/components/schemas/{NULL_NAME}"},
    ]


def store(world, exercise, source: str, summary: dict):
    recording = make_recording(world.patient, exercise, source)
    AnalysisRun.objects.filter(recording=recording).update(
        status=RunStatus.SUCCEEDED, progress=100, summary=summary, score=summary["score"]
    )
    return recording


def test_api_result_equals_the_typed_result_json(api, world, results):
    exercises = {m: make_exercise(world.clinic, n, tutor_source(m)) for n, m in EXERCISES.items()}
    stored = {}
    for (movement, source), result in results.items():
        stored[store(world, exercises[movement], source, result).pk] = result
    listed = api.get(f"/api/v1/patients/{world.patient.pk}/recordings/?fields=result&limit=50")
    by_id = {r["id"]: r["result"] for r in listed.json()["results"]}
    assert len(by_id) == len(results) == 6
    check = validator()
    for pk, result in stored.items():
        detail = api.get(f"/api/v1/recordings/{pk}/").json()
        assert detail["status"] == "succeeded"
        assert detail["result"] == result == AnalysisSummary.from_json(result).to_json()
        assert by_id[str(pk)] == result
        assert check.is_valid(detail["result"])


def test_an_old_run_is_served_in_the_contract_shape(api, world):
    """A run stored before most fields existed: the API answers the typed result's JSON, which
    fits the schema, "not stored" as null where nothing decides it, and the run's one verdict
    (the reading's: the score against the run's pass threshold when no verdict was stored)."""
    old = {
        "frames": 90,
        "fps": 30.0,
        "score": 71.5,
        "landmarks": [{"frame": 3, "type": 1}],
        "repetitions": [{"start": 3, "end": 80, "score": 71.5, "guidance": "slow down"}],
    }
    exercise = make_exercise(world.clinic, "Deep squat", tutor_source("m01"))
    recording = store(world, exercise, "reps/m01_s01_e02.bvh.gz", old)
    result = api.get(f"/api/v1/recordings/{recording.pk}/").json()["result"]
    assert validator().is_valid(result)
    assert result["segmentation"] is None
    reading = reading_of(recording.runs.get())
    assert result["repetitions"][0]["passed"] is reading.repetitions[0]["passed"] is True
    assert result["landmarks"][0]["origin"] == "identified"
    assert result["repetitions"][0]["guidance"] == [{"type": "slow down", "frames": [3, 80]}]


def test_not_stored_stays_distinguishable_from_a_value():
    old = AnalysisSummary.from_json({"repetitions": [{"start": 0, "end": 9, "score": 40.0}]})
    assert old.segmentation is None and old.repetitions[0].passed is None
    new = AnalysisSummary.from_json(
        {
            "segmentation": "fallback",
            "repetitions": [{"start": 0, "end": 9, "score": 40.0, "passed": False}],
        }
    )
    assert new.segmentation == "fallback" and new.repetitions[0].passed is False
