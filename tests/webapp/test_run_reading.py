"""The one reading of a run (`webapp.recordings.reading`): the verdict rule, the shown score, the
stored figures, when a reading is built and dropped, and the same pass count on every page,
list, report and export after a therapist labels a repetition."""

from __future__ import annotations

import csv
import io

import pytest
from django.urls import reverse
from pdfminer.high_level import extract_text
from rest_framework.test import APIClient

from analysis.pipeline.results import RepetitionResult
from tests.personas import make_exercise, make_recording
from webapp.dashboard.home import recent_recordings
from webapp.recordings.models import AnalysisRun, RepetitionLabel, RunReading, RunStatus
from webapp.recordings.reading import (
    ANALYSIS,
    THERAPIST,
    reading_of,
    shown_score,
    verdict,
)
from workers import runs


def rep(score: float, passed: bool | None) -> RepetitionResult:
    return RepetitionResult(start=0, end=9, peak=5, score=score, passed=passed)


def test_the_therapists_label_comes_first_then_the_analysis_then_the_score():
    assert verdict(rep(90.0, True), 70.0, False) == (False, THERAPIST)
    assert verdict(rep(40.0, False), 70.0, True) == (True, THERAPIST)
    assert verdict(rep(90.0, False), 70.0, None) == (False, ANALYSIS)  # the analysis' own verdict
    assert verdict(rep(71.0, None), 70.0, None) == (True, ANALYSIS)  # older runs: the score
    assert verdict(rep(69.9, None), 70.0, None) == (False, ANALYSIS)


def test_a_score_under_the_threshold_is_never_shown_on_it():
    assert shown_score(69.6, 70.0) == 69  # not "70 not passed"
    assert shown_score(69.4, 70.0) == 69
    assert shown_score(70.0, 70.0) == 70
    assert shown_score(85.6, 70.0) == 86
    assert shown_score(49.7, 50.0) == 49


SUMMARY = {
    "frames": 40, "fps": 20.0, "landmarks": [], "score": 74.0, "pass_threshold": 70.0,
    "repetitions": [
        {"start": 0, "end": 9, "peak": 5, "score": 88.0, "passed": True},
        {"start": 10, "end": 19, "peak": 15, "score": 69.6, "passed": False,
         "guidance": [{"type": "too fast", "frames": [10, 19]}]},
        {"start": 20, "end": 29, "peak": 25, "score": 81.0, "passed": None},
    ],
    "advice": {"corrections": [], "went_well": ["Your knees stayed in line."]},
}  # fmt: skip
NOT_THE_EXERCISE = {
    "frames": 40, "fps": 20.0, "landmarks": [], "score": None, "repetitions": [],
    "match": {"fits": False, "message": "This looks like another exercise.", "looks_like": None},
}  # fmt: skip


def ended(recording, summary: dict) -> AnalysisRun:
    """The run of `recording` ended by the worker's state change (`workers.runs.succeed`)."""
    run = recording.runs.get()
    token = runs.claim(str(run.pk), "test-worker")
    assert runs.succeed(str(run.pk), token, summary=summary)
    return AnalysisRun.objects.get(pk=run.pk)


@pytest.fixture
def analysed(world):
    exercise = make_exercise(world.clinic)
    return ended(make_recording(world.patient, exercise), SUMMARY)


def test_a_run_that_ends_stores_its_reading(analysed):
    reading = RunReading.objects.get(run=analysed)
    assert (reading.fits, reading.score) == (True, 74.0)
    assert (reading.repetition_count, reading.passed_count, reading.labelled_count) == (3, 2, 0)
    assert [row["shown_score"] for row in reading.repetitions] == [88, 69, 81]
    assert reading.repetitions[1]["verdict"] == "not passed (score 69, needs 70)"
    assert reading.repetitions[1]["reasons"] == ["Movement too fast."]
    # a failed repetition no correction names is in what to correct: never "nothing to correct"
    assert reading.statements["to_correct"] == ["Repetition 2: Movement too fast."]
    assert reading.statements["went_well"] == ["Your knees stayed in line."]


def test_a_therapists_label_rebuilds_the_reading(world, analysed):
    api = APIClient()
    api.force_authenticate(world.therapist)
    url = f"/api/v1/recordings/{analysed.recording_id}/corrections/"
    answer = api.post(url, {"repetitions": [{"index": 0, "passed": False}]}, format="json")
    assert answer.status_code == 200
    reading = RunReading.objects.get(run=analysed)
    assert (reading.passed_count, reading.labelled_count) == (1, 1)
    assert reading.repetitions[0]["by"] == THERAPIST and not reading.repetitions[0]["passed"]
    assert reading.repetitions[0]["reasons"] == ["Not done well, in the therapist's judgement."]
    assert "Repetition 1 marked not passed by the therapist." in reading.statements["therapist"]


def test_writing_a_summary_or_a_label_drops_the_reading_and_the_next_read_builds_it(analysed):
    RepetitionLabel.objects.create(run=analysed, index=2, passed=False)
    assert not RunReading.objects.filter(run=analysed).exists()
    assert reading_of(AnalysisRun.objects.get(pk=analysed.pk)).passed_count == 1
    AnalysisRun.objects.filter(pk=analysed.pk).update(summary={**SUMMARY, "repetitions": []})
    assert not RunReading.objects.filter(run=analysed).exists()
    assert reading_of(AnalysisRun.objects.get(pk=analysed.pk)).repetition_count == 0


def history_passed(client, patient) -> list[str]:
    body = client.get(f"/api/v1/patients/{patient.pk}/history.csv").content.decode()
    return [row["repetitions passed (count)"] for row in csv.DictReader(io.StringIO(body))]


def fhir_passed(client, patient) -> list[float]:
    bundle = client.get(f"/api/v1/patients/{patient.pk}/fhir/").json()
    return [
        c["valueQuantity"]["value"]
        for e in bundle["entry"]
        for c in e["resource"].get("component", [])
        if c["code"]["coding"][0]["code"] == "repetitions-passed"
    ]


def test_every_door_counts_the_therapists_verdict(client, world, analysed):
    """After one label: the API result, the results endpoint, the list, the history CSV, FHIR,
    the PDF and the recording page all count 1 of 3, read from the one stored reading."""
    RepetitionLabel.objects.create(run=analysed, index=0, passed=False, author=world.therapist)
    api = APIClient()
    api.force_authenticate(world.therapist)
    pk = analysed.recording_id
    result = api.get(f"/api/v1/recordings/{pk}/").json()["result"]
    assert [r["passed"] for r in result["repetitions"]] == [False, False, True]
    data = api.get(f"/api/v1/recordings/{pk}/result/").json()
    assert (
        data["reading"]["passed_count"] == 1 and data["repetitions"][0]["verdict_by"] == THERAPIST
    )
    listed = api.get(f"/api/v1/patients/{world.patient.pk}/recordings/").json()["results"]
    assert (listed[0]["passed"], listed[0]["repetitions"], listed[0]["fits"]) == (1, 3, True)
    assert history_passed(api, world.patient) == ["1"]
    assert fhir_passed(api, world.patient) == [1]
    client.force_login(world.therapist)
    page = client.get(reverse("recordings:detail", args=[pk])).content.decode()
    assert '<span id="passed-count">1</span> passed' in page
    assert "not passed: the therapist&#x27;s verdict (analysis score 88, needs 70)" in page
    patient_page = client.get(reverse("patients:detail", args=[world.patient.pk])).content.decode()
    assert "1 of 3" in patient_page
    # the page's result.json is the API's answer, through the same view
    assert client.get(reverse("recordings:result", args=[pk])).json() == data


def test_the_pdf_says_the_readings_count(world, analysed):
    from webapp.reports.content import recording_content
    from webapp.reports.pdf import recording_pdf

    RepetitionLabel.objects.create(run=analysed, index=2, passed=False, author=world.therapist)
    pdf = recording_pdf(recording_content(analysed.recording))
    text = extract_text(io.BytesIO(pdf))
    assert "1 of 3 repetitions passed" in " ".join(text.split())


def test_lists_say_a_recording_does_not_show_the_exercise(client, world):
    exercise = make_exercise(world.clinic)
    run = ended(make_recording(world.patient, exercise), NOT_THE_EXERCISE)
    assert RunReading.objects.get(run=run).fits is False
    row = recent_recordings(world.therapist)[0]
    assert row.status_words == "Does not show the exercise"
    client.force_login(world.therapist)
    page = client.get(reverse("patients:detail", args=[world.patient.pk])).content.decode()
    assert "Does not show the exercise" in page and ">Succeeded<" not in page
    home = client.get(reverse("dashboard:home")).content.decode()
    assert "Does not show the exercise" in home


def test_runs_stored_before_readings_get_one_on_first_read(world):
    """A run written without the worker (a bulk load, an older release) is read the same."""
    exercise = make_exercise(world.clinic)
    recording = make_recording(world.patient, exercise)
    AnalysisRun.objects.filter(recording=recording).update(
        status=RunStatus.SUCCEEDED, summary=SUMMARY
    )
    assert not RunReading.objects.exists()
    api = APIClient()
    api.force_authenticate(world.therapist)
    listed = api.get(f"/api/v1/patients/{world.patient.pk}/recordings/").json()["results"]
    assert listed[0]["passed"] == 2
    assert RunReading.objects.get().passed_count == 2  # stored: the next list reads it


def test_compare_never_shows_a_failed_score_on_the_threshold(client, world, analysed):
    """Issue 38: "70 passed" beside "70 not passed"; a 69.6 is shown 69 beside "not passed"."""
    pk, patient = analysed.recording_id, world.patient.pk
    client.force_login(world.therapist)
    url = reverse("patients:compare", args=[patient]) + f"?a={pk}&b={pk}"
    page = " ".join(client.get(url).content.decode().split())
    assert '<td>69</td><td class="verdict failed">not passed</td>' in page
    assert '<td>70</td><td class="verdict failed">' not in page
    assert "3 repetitions done, 2 passed" in page
