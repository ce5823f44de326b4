"""A therapist's and a patient's day with the demo clinic, in a real browser (issue 18).

1. Every recording of a patient is reachable from the patient's page, with its score and status,
   older ones page by page; the home page keeps its recent list.
2. The recording and progress pages speak plain words: body parts, "your movement" / "the
   reference adjusted to your level", level instead of γ, seconds, units on every chart axis.
7. A patient uploads for themselves only, among the exercises prescribed to them; a pain of 6/10
   or more puts them on the therapist's attention list.
8. The progress PDF draws range of motion per exercise; the 3D viewer draws no bone from a
   floor-level placement root to the hips (Bandai-Namco's rigs).

With E2E_DOCS=1 the patient page is saved to docs/img/patient-page.png (README).
"""

from __future__ import annotations

import io
import os
import re
from pathlib import Path

import pytest

from tests.e2e.conftest import log_in

ROOT = Path(__file__).resolve().parents[2]
SESSION = ROOT / "data/ui-prmd/sessions/m01_s01_correct.bvh.gz"
DOCS = ROOT / "docs" / "img"
RIG_NAME = re.compile(r"\b(Left|Right)[A-Z][a-z]+|\bHeadTip\b|\bWaist\b|_[LR]\b|joint_Root")
pytestmark = pytest.mark.e2e


def pat():
    from webapp.patients.models import Patient

    return Patient.objects.get(display_name="Pat Patient")


def open_patient_page(page, base_url: str) -> None:
    page.goto(f"{base_url}/patients/")
    page.click("text=Pat Patient")
    page.wait_for_selector("#recordings")


def add_older_recordings(count: int) -> None:
    """Older copies of a demo recording (distinct checksums), so the list has a second page."""
    import datetime

    from django.utils import timezone

    from webapp.recordings.models import AnalysisRun, Recording, RunStatus

    source = pat().recordings.order_by("uploaded_at").first()
    run = source.latest_succeeded_run()
    for i in range(count):
        copy = Recording.objects.get(pk=source.pk)
        copy.pk, copy.checksum = None, f"{i:064d}"
        copy.save()
        when = timezone.now() - datetime.timedelta(days=60 + i)
        Recording.objects.filter(pk=copy.pk).update(uploaded_at=when)
        AnalysisRun.objects.create(
            recording=copy,
            model=run.model,
            status=RunStatus.SUCCEEDED,
            summary={**run.summary, "score": 40 + i},
            arrays=run.arrays.name,
        )


def test_1_every_recording_of_a_patient_opens_from_their_page(page, live_server, demo):
    log_in(page, live_server.url)
    assert page.locator("#recent-rows tr a").count() >= 4  # home keeps its recent list
    open_patient_page(page, live_server.url)
    rows = page.locator("#recordings tbody tr")
    assert rows.count() == pat().recordings.count() == 4
    for i in range(rows.count()):
        row = rows.nth(i)
        assert row.locator("a").count() == 1
        assert row.locator(".score").inner_text().isdigit()  # every demo recording is scored
        assert row.locator(".status").inner_text() == "Succeeded"
    if os.environ.get("E2E_DOCS"):
        DOCS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(DOCS / "patient-page.png"), full_page=True)

    add_older_recordings(22)  # 26 in all: two pages of 20
    page.reload()
    assert "26" in page.inner_text("#recordings h2")
    page.click("#recordings .pagination >> text=Next")
    page.wait_for_url("**recordings_page=2**")
    last = page.locator("#recordings tbody tr").last
    assert last.locator(".score").inner_text() == str(40 + 21)  # the oldest copy's own score
    last.locator("a").click()
    page.wait_for_url("**/recordings/*/")
    assert page.inner_text("#run-state") == "Succeeded"
    assert "61" in page.inner_text(".score")


def test_2_recording_and_progress_pages_speak_plain_words(page, live_server, demo):
    log_in(page, live_server.url)  # patients get their own lay pages (test_patient_phone.py)
    open_patient_page_as_patient(page, live_server.url)
    page.locator("#recordings tbody tr a").first.click()
    page.wait_for_selector("#viewer[data-ready='1']")
    toggles = page.inner_text("#skeleton-toggles")
    assert "your movement" in toggles and "the reference adjusted to your level" in toggles
    assert re.fullmatch(r"\d+\.\d\d s", page.inner_text("#frame-label"))
    assert re.search(r"/ 100 · \d+ repetitions?\b", page.inner_text(".score"))
    axes = page.locator("#chart-angles .g-xtitle, #chart-angles .g-ytitle").all_text_contents()
    assert axes == ["time (s)", "angle (°)"]
    legend = page.text_content("#chart-angles .legend")
    # the clinical angles of the table, each with its normal range; never body segments
    assert re.search(r"(Left|Right) [a-z ]+ \(normal -?\d+° to \d+°\)", legend), legend
    assert not re.search(r"(left|right) (thigh|upper arm|lower leg|foot|collarbone)", legend)
    text = page.inner_text("body") + legend
    assert not RIG_NAME.search(text) and "γ" not in text and "tutor_adjusted" not in text

    page.goto(f"{live_server.url}/patients/{pat().pk}/progress/")
    page.wait_for_selector("#progress[data-ready='1']")
    titles = page.locator(".g-ytitle").all_text_contents()
    for title in ("score (0–100)", "range of motion (°)", "level (0–1)"):
        assert title in titles, titles
    charts = ["chart-score", "chart-rom", "chart-gamma", "chart-reps", "chart-adherence"]
    for chart in charts:  # every axis of every chart says what it measures
        assert page.locator(f"#{chart} .g-xtitle").text_content().strip()
        assert page.locator(f"#{chart} .g-ytitle").text_content().strip()
    assert page.locator("#chart-rom .legend .traces").count() <= 4  # the body parts moved most
    options = page.locator("#exercise-filter option").all_text_contents()
    assert "Deep squat" in options and "Shoulder abduction" in options  # one exercise at a time
    legend = page.text_content("#chart-rom .legend")
    text = page.inner_text("body")
    assert "Level per body part" in text and "γ" not in text and not RIG_NAME.search(legend)


def open_patient_page_as_patient(page, base_url: str) -> None:
    page.goto(f"{base_url}/patients/{pat().pk}/")
    page.wait_for_selector("#recordings")


def test_7_a_patient_uploads_for_themselves_and_pain_reaches_the_therapist(
    browser, page, live_server, demo
):
    log_in(page, live_server.url, "demo-patient")
    page.click("text=Upload a session")
    page.wait_for_selector("#id_exercise")
    assert page.locator("#id_patient").count() == 0  # nobody to pick: the patient is themselves
    offered = [o for o in page.locator("#id_exercise option").all_inner_texts() if o[:1] != "-"]
    prescribed = sorted(p.exercise.name for p in pat().prescriptions.select_related("exercise"))
    assert sorted(offered) == prescribed == ["Deep squat", "Shoulder abduction"]
    page.select_option("#id_exercise", label="Deep squat")
    page.set_input_files("#id_file", str(SESSION))
    page.fill("#id_pain_score", "7")
    page.click("button[type=submit]")
    page.wait_for_url("**/recordings/*/")
    page.wait_for_function(
        "document.getElementById('run-status').dataset.status === 'succeeded'", timeout=180_000
    )
    newest = pat().recordings.order_by("-uploaded_at").first()
    assert (newest.pain_score, newest.uploaded_by.username) == (7, "demo-patient")

    therapist = browser.new_context(viewport={"width": 1280, "height": 1000}).new_page()
    log_in(therapist, live_server.url)
    item = therapist.locator("#attention .attention-item", has_text="Pat Patient")
    text = item.inner_text().lower()  # the tag is in capitals by style
    assert "pain reported" in text and "pain 7/10" in text
    item.locator("a", has_text="pain 7/10").click()
    therapist.wait_for_url(f"**/recordings/{newest.pk}/")
    therapist.context.close()


def test_8_progress_pdf_draws_range_of_motion_per_exercise(page, live_server, demo):
    from pypdf import PdfReader

    log_in(page, live_server.url)
    page.goto(f"{live_server.url}/patients/{pat().pk}/progress/")
    with page.expect_download() as download:
        page.click("#progress-pdf")
    text = " ".join(
        p.extract_text()
        for p in PdfReader(io.BytesIO(Path(download.value.path()).read_bytes())).pages
    )
    # each exercise's chart plots the clinical angles it moves most (knees and hips for a squat)
    assert "Deep squat: range of the joint angles moved most, by session" in text
    assert "Shoulder abduction: range of the joint angles moved most, by session" in text
    assert "range of motion (°)" in text and "date of the session" in text
    assert not RIG_NAME.search(text)


BANDAI_SHAPE = """async () => {
  const THREE = await import("three");
  const { Playback } = await import("/static/js/viewer.js");
  // joint_Root (floor, zero offset) -> Hips -> Spine, and two legs from the hips.
  const parents = [-1, 0, 1, 1, 3, 1, 5];
  const pose = [[0, 0, 0], [0, 95, 0], [0, 120, 0],
    [10, 90, 0], [10, 45, 0], [-10, 90, 0], [-10, 45, 0]];
  const frames = 2, joints = parents.length;
  const positions = new Float32Array(frames * joints * 3);
  for (let f = 0; f < frames; f++) pose.forEach((p, j) => positions.set(p, (f * joints + j) * 3));
  const root = document.createElement("div");
  root.innerHTML = '<canvas style="width:320px;height:240px"></canvas>';
  document.body.append(root);
  const meta = {
    frames, joints, fps: 30, parents,
    names: ["joint_Root", "Hips", "Spine", "LeftUpLeg", "LeftLeg", "RightUpLeg", "RightLeg"],
    skeletons: [{ key: "patient", label: "your movement" }],
    landmarks: [], repetitions: [], feedback: [], assessment: [],
  };
  const playback = new Playback(root, meta, positions);
  const m = new THREE.Matrix4(), scale = new THREE.Vector3();
  const at = new THREE.Vector3(), q = new THREE.Quaternion();
  const size = (mesh, j) => {
    mesh.getMatrixAt(j, m); m.decompose(at, q, scale); return scale.length();
  };
  const { bones, joints: spheres } = playback.skeletons[0];
  return {
    bones: parents.map((_, j) => size(bones, j)),
    joints: parents.map((_, j) => size(spheres, j)),
  };
}"""


def test_8_viewer_draws_no_bone_from_a_floor_level_root(page, live_server, demo):
    log_in(page, live_server.url)
    recording = pat().recordings.first()
    page.goto(f"{live_server.url}/recordings/{recording.pk}/")  # a page with the viewer's imports
    page.wait_for_selector("#viewer[data-ready='1']")
    sizes = page.evaluate(BANDAI_SHAPE)
    assert sizes["bones"][1] == 0  # root → hips: no "third leg"
    assert sizes["joints"][0] == 0  # nor a sphere on the floor
    assert all(s > 0 for s in sizes["bones"][2:])  # the body's own bones are drawn
    assert all(s > 0 for s in sizes["joints"][1:])
