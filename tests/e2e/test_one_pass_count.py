"""One pass count everywhere, in a real browser: a therapist marks one passed repetition "not
passed" with the recording page's button, and the recording page, the patient's own pages, the
compare page, the patient's list of recordings, the PDF (its text), the history CSV, FHIR and the
API all say 2 of 4 passed (3 before the label).

The runs end through the worker's own state change (`workers.runs.succeed`), which builds their
readings, as a real analysis does; the label goes through the page's form.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import pytest
from django.core.files.base import ContentFile
from pypdf import PdfReader

from tests.e2e.conftest import log_in, signed_in_page
from tests.e2e.test_compare import arrays_file
from tests.personas import PASSWORD, make_exercise, make_recording, make_world
from workers import runs

pytestmark = pytest.mark.e2e


def summary(scores: list[float], passed: list[bool]) -> dict:
    return {
        "frames": 80, "fps": 20.0, "landmarks": [], "score": sum(scores) / len(scores),
        "pass_threshold": 70.0,
        "repetitions": [
            {"start": 20 * i, "end": 20 * i + 19, "peak": 20 * i + 10, "score": s, "passed": p,
             "reasons": [] if p else ["Raise your arm higher, by about 20°."]}
            for i, (s, p) in enumerate(zip(scores, passed, strict=True))
        ],
        "advice": {"corrections": [], "went_well": []},
    }  # fmt: skip


def analysed(patient, exercise, data: dict):
    """A recording whose run the worker ended with ``data`` (its arrays stored for the viewer)."""
    recording = make_recording(patient, exercise)
    run = recording.runs.get()
    run.arrays.save("run.npz", ContentFile(arrays_file(80, 4)), save=True)
    token = runs.claim(str(run.pk), "browser-test")
    assert runs.succeed(str(run.pk), token, summary=data)
    return recording


@pytest.fixture
def labelled_session(transactional_db, eager_celery):
    world = make_world()
    exercise = make_exercise(world.clinic)
    first = analysed(world.patient, exercise, summary([60.0, 65.0, 80.0, 50.0], [0, 0, 1, 0]))
    latest = analysed(world.patient, exercise, summary([88.0, 91.0, 76.0, 64.0], [1, 1, 1, 0]))
    return world, first, latest


def text_of(page, url: str, selector: str) -> str:
    page.goto(url)
    return " ".join(page.inner_text(selector).split())


def fetched(page, url: str):
    answer = page.request.get(url)
    assert answer.ok, f"{url}: {answer.status}"
    return answer


def pdf_text(page, recording_url: str) -> str:
    """The text of the PDF the recording page's link downloads, spaces collapsed."""
    page.goto(recording_url)
    with page.expect_download() as download:
        page.click("#report-pdf")
    content = Path(download.value.path()).read_bytes()
    text = " ".join(p.extract_text() for p in PdfReader(io.BytesIO(content)).pages)
    return " ".join(text.split())


def test_a_therapists_label_is_the_count_on_every_page_and_export(
    page, live_server, labelled_session
):
    world, first, latest = labelled_session
    base, patient = live_server.url, world.patient.pk
    log_in(page, base, "therapist", PASSWORD)
    page.goto(f"{base}/recordings/{latest.pk}/")
    assert page.inner_text("#passed-count") == "3"
    page.click("button[data-label='1']")  # repetition 1: passed by the analysis
    page.wait_for_selector("#repetitions .verdict.failed >> text=the therapist")
    assert page.inner_text("#passed-count") == "2"

    row = text_of(page, f"{base}/patients/{patient}/", f"tr[data-recording='{latest.pk}']")
    assert "2 of 4" in row  # the patient's list of recordings
    side = text_of(
        page, f"{base}/patients/{patient}/compare/?a={first.pk}&b={latest.pk}", "#compare-side-b"
    )
    assert "4 repetitions done, 2 passed" in side
    assert "2 of 4 repetitions passed" in pdf_text(page, f"{base}/recordings/{latest.pk}/")

    history = fetched(page, f"{base}/api/v1/patients/{patient}/history.csv").text()
    rows = list(csv.DictReader(io.StringIO(history)))
    assert [r["repetitions passed (count)"] for r in rows] == ["1", "2"]
    bundle = fetched(page, f"{base}/api/v1/patients/{patient}/fhir/").json()
    passed = [
        c["valueQuantity"]["value"]
        for e in bundle["entry"]
        for c in e["resource"].get("component", [])
        if c["code"]["coding"][0]["code"] == "repetitions-passed"
    ]
    assert sorted(passed) == [1, 2]

    result = fetched(page, f"{base}/api/v1/recordings/{latest.pk}/result/").json()
    assert result["reading"]["passed_count"] == 2
    assert sum(r["passed"] for r in result["repetitions"]) == 2
    detail = fetched(page, f"{base}/api/v1/recordings/{latest.pk}/").json()
    assert sum(r["passed"] for r in detail["result"]["repetitions"]) == 2
    listed = fetched(page, f"{base}/api/v1/patients/{patient}/recordings/").json()["results"]
    assert {r["id"]: r["passed"] for r in listed} == {str(latest.pk): 2, str(first.pk): 1}

    with signed_in_page(page.context.browser, base, "patient", PASSWORD) as own:
        assert own.inner_text("#reps-well") == "2"  # their home: the last session
        home = " ".join(own.inner_text(f"tr[data-recording='{latest.pk}']").split())
        assert "2 of 4 done well" in home
        assert text_of(own, f"{base}/recordings/{latest.pk}/", "#reps-well") == "2"
        progress = text_of(own, f"{base}/my/progress/", "main")
        assert re.search(r"2 of 4 repetitions done well", progress)
