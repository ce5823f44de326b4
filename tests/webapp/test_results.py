"""The results data of an analysed recording (web JSON and API), including the most similar
earlier recordings of the clinic (paper 002 retrieval), scoped to what the viewer may see."""

from __future__ import annotations

import pytest
from django.urls import reverse
from rest_framework.test import APIClient

from tests.personas import make_exercise, make_recording
from workers.analysis_task import analyse_run


def analysed(patient, exercise, source: str):
    recording = make_recording(patient, exercise, source=source)
    assert analyse_run(str(recording.runs.get().pk)) == "succeeded"
    return recording


@pytest.fixture
def recordings(world):
    exercise = make_exercise(world.clinic)
    mine_early = analysed(world.patient, exercise, "reps/m01_s01_e02.bvh.gz")
    theirs = analysed(world.other_patient, exercise, "reps/m01_s01_e03_inc.bvh.gz")
    latest = analysed(world.patient, exercise, "reps/m01_s01_e03.bvh.gz")
    return mine_early, theirs, latest


def test_result_json_holds_the_results_data(client, world, recordings):
    client.force_login(world.therapist)
    latest = recordings[2]
    body = client.get(reverse("recordings:result", kwargs={"pk": latest.pk})).json()
    assert body["status"] == "succeeded" and body["model_version"] == 1
    assert body["repetitions"] and {"start", "end", "score"} <= set(body["repetitions"][0])
    assert {"frame", "type", "levels", "type_name"} <= set(body["assessment"][0])
    assert body["assessment"][0]["type_name"] in {"start", "end of range"}
    assert isinstance(body["feedback"], list)
    assert 0 <= body["metrics"]["score"] <= 100
    assert body["metrics"]["repetition_count"] == len(body["repetitions"])
    assert body["gamma"] and all(isinstance(v, float) for v in body["gamma"].values())
    similar = body["similar"]
    assert {s["recording"] for s in similar} == {str(recordings[0].pk), str(recordings[1].pk)}
    assert [s["distance"] for s in similar] == sorted(s["distance"] for s in similar)


def test_patient_sees_only_their_own_similar_recordings(client, world, recordings):
    client.force_login(world.patient_user)
    body = client.get(reverse("recordings:result", kwargs={"pk": recordings[2].pk})).json()
    assert [s["recording"] for s in body["similar"]] == [str(recordings[0].pk)]


def test_first_recording_has_no_similar_and_queued_run_has_no_result(client, world):
    exercise = make_exercise(world.clinic)
    recording = make_recording(world.patient, exercise)
    client.force_login(world.therapist)
    body = client.get(reverse("recordings:result", kwargs={"pk": recording.pk})).json()
    assert body["status"] == "queued" and "repetitions" not in body
    analyse_run(str(recording.runs.get().pk))
    body = client.get(reverse("recordings:result", kwargs={"pk": recording.pk})).json()
    assert body["status"] == "succeeded" and body["similar"] == []


def test_api_result_matches_and_is_scoped(world, recordings):
    api = APIClient()
    api.force_authenticate(world.therapist)
    url = f"/api/v1/recordings/{recordings[2].pk}/result/"
    body = api.get(url).json()
    assert body["recording"] == str(recordings[2].pk) and len(body["similar"]) == 2
    api.force_authenticate(world.outsider)
    assert api.get(url).status_code == 404
