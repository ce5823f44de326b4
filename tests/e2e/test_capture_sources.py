"""Capture files other than BVH through the upload form, against the site started the way
`make run` starts it (server and a real Celery worker, `tests/local_server.py`):

- the Pose2Sim `.trc` (21 keypoints) is analysed against a reference made from it;
- the phone video of two squats is analysed by the worker (MediaPipe Pose finds the person in its
  frames, the progress bar moving meanwhile) and counts 2 repetitions against a squat reference
  made from it (`tests/analysis/fixtures/capture/make_squat_reference.py`).

Both uploads answer at once: the video's frames are read by the worker, not the web server.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.e2e.conftest import signed_in_page
from tests.e2e.test_upload_flow import submit_upload, watch_until_succeeded
from tests.local_server import LocalServer
from tests.personas import PASSWORD

pytestmark = pytest.mark.e2e
CAPTURE = Path(__file__).resolve().parents[1] / "analysis/fixtures/capture"
TRC = CAPTURE / "pose2sim_balancing.trc"
VIDEO = CAPTURE / "side_squat_2reps.mp4"
SETUP = """
from pathlib import Path
from django.core.files.base import ContentFile
from analysis.bvh import dumps
from analysis.sources import read_recording
from tests.analysis.fixtures.capture import make_squat_reference as squat
from tests.personas import make_user
from webapp.accounts.models import Clinic, Role
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient

clinic = Clinic.objects.create(name="Capture clinic")
therapist = make_user("capturer", clinic, Role.THERAPIST)
patient = Patient.objects.create(clinic=clinic, display_name="Ann Example")
patient.therapists.add(therapist)
trc = squat.HERE / "pose2sim_balancing.trc"
balance = read_recording(trc.name, trc.read_bytes()).motion
for name, tutor, frames, types in (
    ("Single-leg balance", dumps(balance).encode(), [0, 50, 99], [1, 2, 1]),
    ("Back squat", squat.REFERENCE.read_bytes(), list(squat.KEY_POSE_FRAMES),
     list(squat.KEY_POSE_TYPES)),
):
    exercise = Exercise(clinic=clinic, name=name, tutor_landmark_frames=frames,
                        tutor_landmark_types=types,
                        landmark_type_names={"1": "start", "2": "end of range"})
    suffix = ".bvh.gz" if tutor[:2] == b"\\x1f\\x8b" else ".bvh"
    exercise.tutor_file.save("tutor" + suffix, ContentFile(tutor), save=False)
    exercise.save()
"""


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    server = LocalServer(tmp_path_factory.mktemp("make-run"), demo=False, setup=SETUP)
    with server:
        yield server


@pytest.fixture
def therapist_page(browser, site):
    with signed_in_page(browser, site.url, "capturer", PASSWORD) as page:
        yield page


def repetitions_counted(page) -> int:
    text = page.inner_text("p.score")
    found = re.search(r"(\d+) repetitions?", text)
    assert found, text
    return int(found.group(1))


def test_a_trc_file_is_analysed_against_a_reference_made_from_it(therapist_page, site):
    page = therapist_page
    seconds = submit_upload(page, site.url, TRC, exercise="Single-leg balance")
    page.wait_for_url("**/recordings/*/")
    assert seconds < 10, f"the upload took {seconds:.1f} s"
    watch_until_succeeded(page, site)
    page.reload()
    assert repetitions_counted(page) == 1
    assert "marker or keypoint positions (.trc)" in page.inner_text("#measurement-source")


def test_the_phone_video_counts_two_squats(therapist_page, site):
    page = therapist_page
    seconds = submit_upload(page, site.url, VIDEO, exercise="Back squat")
    page.wait_for_url("**/recordings/*/")
    # the video's frames are the worker's work: the upload answers first
    assert page.get_attribute("#run-status", "data-status") in ("queued", "running")
    assert seconds < 10, f"the upload took {seconds:.1f} s"
    seen = watch_until_succeeded(page, site)
    assert any(2 < p < 50 for p in seen), seen  # the bar moved while the frames were read
    page.reload()
    assert repetitions_counted(page) == 2
    # beside the joint angles, how far a phone video's measurements can be trusted
    assert "Measured from a phone video" in page.inner_text("#measurement-source")
    video_beside_the_skeletons_in_step(page)


def video_beside_the_skeletons_in_step(page) -> None:
    """The uploaded video plays next to the 3D viewer (muted, labelled), and seeking either one
    moves the other: the skeleton frame is the video's time × the playback's frame rate."""
    page.wait_for_selector("#viewer[data-ready='1']")
    video, canvas = page.locator("#recording-video"), page.locator("#viewer-canvas")
    assert video.get_attribute("aria-labelledby") == "video-label"
    assert video.evaluate("v => v.muted && !v.autoplay")
    side, stage = video.bounding_box(), canvas.bounding_box()
    assert side["x"] + side["width"] <= stage["x"], (side, stage)  # beside it, to its left
    assert side["y"] < stage["y"] + stage["height"] and stage["y"] < side["y"] + side["height"]
    page.wait_for_function("document.getElementById('recording-video').readyState >= 1")
    fps = page.evaluate("window.physioPlayback.meta.fps")

    video.evaluate("v => { v.currentTime = 3.0; }")  # seeking the video moves the skeletons
    expected = f"{round(3.0 * fps) / fps:.2f} s"
    page.wait_for_function(
        f"document.getElementById('frame-label').textContent === '{expected}'", timeout=10_000
    )
    assert page.evaluate("window.physioPlayback.frame") == round(3.0 * fps)

    page.click("#step-fwd")  # moving the skeletons seeks the video
    frame = page.evaluate("window.physioPlayback.frame")
    page.wait_for_function(
        f"Math.abs(document.getElementById('recording-video').currentTime - {frame / fps}) < 0.02"
    )
    page.click("#play")  # playing either plays both
    page.wait_for_function("!document.getElementById('recording-video').paused")
    page.wait_for_function(f"window.physioPlayback.frame > {frame + 5}")
    video.evaluate("v => v.pause()")  # and pausing the video pauses the skeletons
    page.wait_for_function("document.getElementById('play').textContent === 'Play'")
    assert not page.evaluate("window.physioPlayback.playing")
