"""The guide for clinics (docs/GUIDE.md, the site's Help page) walked in a real browser: every
page it shows opens from where the guide says, with the buttons it names, and each picture in
the guide is taken here.

With E2E_DOCS=1 (`make bench-browser`) the pictures are saved to docs/img/guide-*.png, where the
guide and the /help/ page read them, and the demo's scores they show to
docs/img/guide-figures.json; otherwise they go to a temporary folder, and the scores of the running
demo must equal the saved ones: pictures showing scores the demo no longer has fail the test until
they are taken again.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest

from tests.e2e.conftest import log_in

pytestmark = pytest.mark.e2e
ROOT = Path(__file__).resolve().parents[2]
GUIDE = ROOT / "docs" / "GUIDE.md"
FIGURES = ROOT / "docs" / "img" / "guide-figures.json"


def demo_scores() -> dict[str, list[int]]:
    """Each analysed demo recording's score and its repetitions' scores, by file name: the
    figures the guide's pictures show (home, patient, recording, progress pages)."""
    from webapp.recordings.models import Recording

    scores = {}
    for recording in Recording.objects.all():
        if run := recording.latest_succeeded_run():
            result = run.result
            reps = [round(rep.score) for rep in result.repetitions]
            scores[recording.original_name] = [round(result.score), *reps]
    return dict(sorted(scores.items()))


def shown_scores(page) -> list[int]:
    """The recording page's score and the score column of its repetition table."""
    cells = page.locator("#repetitions tbody tr td:nth-child(3)").all_inner_texts()
    return [int(page.locator(".score strong").inner_text()), *(int(c) for c in cells)]


def guide_pictures() -> list[str]:
    return re.findall(r"!\[[^\]]+\]\(img/(guide-[a-z0-9-]+\.png)\)", GUIDE.read_text())


@pytest.fixture
def shots(tmp_path) -> Path:
    folder = ROOT / "docs" / "img" if os.environ.get("E2E_DOCS") else tmp_path
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def snap(page, folder: Path, name: str, taken: list[str], **options) -> None:
    page.wait_for_load_state("networkidle")
    page.screenshot(path=str(folder / name), **options)
    taken.append(name)


def open_link(page, name: str) -> None:
    page.get_by_role("link", name=name).first.click()
    page.wait_for_load_state()


def test_the_guide_walks_through_the_demo_clinic(page, live_server, demo, shots):
    from webapp.patients.models import Patient

    base = live_server.url
    taken: list[str] = []
    page.set_viewport_size({"width": 1280, "height": 860})
    log_in(page, base, "demo-therapist")
    snap(page, shots, "guide-home.png", taken)

    page.click("details.usermenu > summary")
    for item in ("Change password", "Two-factor sign-in", "API tokens", "API documentation"):
        assert page.locator(".usermenu-items a", has_text=item).is_visible(), item
    snap(page, shots, "guide-menu.png", taken, clip={"x": 640, "y": 0, "width": 640, "height": 360})
    page.click("details.usermenu > summary")

    # 1. A reference: Exercises → New exercise.
    open_link(page, "Exercises")
    open_link(page, "New exercise")
    page.fill("#id_name", "Lunge")
    page.fill("#id_description", "Step forward into a lunge and back, hands on the hips.")
    snap(page, shots, "guide-new-exercise.png", taken)

    # 2. Key poses: the exercise's page → Mark key poses; Build model is on the exercise's page.
    open_link(page, "Exercises")
    open_link(page, "Deep squat")
    assert page.get_by_role("button", name="Build model").is_visible()
    open_link(page, re.compile("Mark key poses"))
    page.locator("#annotate").wait_for()
    snap(page, shots, "guide-key-poses.png", taken)

    # 3. Prescribe: Patients → the patient → Prescribe.
    open_link(page, "Patients")
    open_link(page, "Pat Patient")
    for button in ("Progress", "PDF report", "Download history (CSV)", "Prescribe"):
        assert page.get_by_role("link", name=button).first.is_visible(), button
    snap(page, shots, "guide-patient.png", taken)
    open_link(page, "Prescribe")
    assert page.locator("#id_sessions_per_week").is_visible()
    snap(page, shots, "guide-prescribe.png", taken)

    # 4. A result: the newest recording, opened from the patient page's list.
    page.go_back()
    newest = Patient.objects.get(display_name="Pat Patient").recordings.latest("uploaded_at")
    page.locator(f"a[href='/recordings/{newest.pk}/']").first.click()
    page.wait_for_selector("#viewer[data-ready='1']")
    assert re.search(r"Score \d+ / 100", page.locator(".score").inner_text())
    assert page.locator("#repetitions tbody tr").count() >= 1
    # The picture shows the demo's own figures for this recording.
    assert shown_scores(page) == demo_scores()[newest.original_name]
    snap(page, shots, "guide-recording.png", taken)
    page.locator("#viewer").scroll_into_view_if_needed()
    page.locator("#viewer").screenshot(path=str(shots / "guide-playback.png"))
    taken.append("guide-playback.png")

    # 5. Scores and levels across sessions: the Progress button of the patient page.
    page.goto(f"{base}/patients/{newest.patient_id}/")
    open_link(page, "Progress")
    page.wait_for_selector("#progress[data-ready='1']")
    top = {"x": 0, "y": 0, "width": 1280, "height": 1500}  # score, range of motion, levels
    snap(page, shots, "guide-progress.png", taken, full_page=True, clip=top)

    # The Help link on every page opens this guide, pictures included.
    open_link(page, "Help")
    assert page.locator("h1").first.inner_text() == "Guide for clinics"
    assert sorted(taken) == sorted(guide_pictures())
    for picture in page.locator(".guide img").all():
        loaded = picture.evaluate("img => img.complete && img.naturalWidth > 0")
        assert loaded, picture.get_attribute("src")
    for name in taken:
        assert (shots / name).stat().st_size > 10_000, name
    if os.environ.get("E2E_DOCS"):
        FIGURES.write_text(json.dumps({"scores": demo_scores()}, indent=1) + "\n")
    saved = json.loads(FIGURES.read_text())["scores"]
    assert saved == demo_scores(), "the guide's pictures show other scores: `make bench-browser`"
