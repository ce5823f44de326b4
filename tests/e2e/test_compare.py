"""The compare page in a real browser: two 3D viewers side by side, one play button driving both
time displays together, and no horizontal overflow at 1280 px.

Each recording's run is written directly (what the worker stores): a summary with repetitions
and clinical angles, and an arrays file with a small swinging skeleton. The two recordings have
different lengths and frame rates, so staying in step is not a coincidence of equal takes.
"""

from __future__ import annotations

import datetime
import io
import re

import numpy as np
import pytest
from django.core.files.base import ContentFile

from tests.e2e.conftest import log_in as sign_in
from tests.personas import PASSWORD, make_exercise, make_recording, make_world
from webapp.recordings.models import Recording, RunStatus

pytestmark = pytest.mark.e2e

PARENTS = np.array([-1, 0, 1, 2, 1], dtype=np.int32)
NAMES = np.array(["Hips", "Spine", "Neck", "Head", "Arm"])


def swinging_skeleton(frames: int, repetitions: int) -> np.ndarray:
    """(frames, 5, 3) cm: a standing chain whose arm swings `repetitions` times."""
    t = np.linspace(0.0, 2 * np.pi * repetitions, frames)
    base = np.array([[0, 90, 0], [0, 120, 0], [0, 150, 0], [0, 165, 0], [0, 140, 0]], float)
    positions = np.repeat(base[None], frames, axis=0)
    positions[:, 4, 0] = 30 * np.cos(t)
    positions[:, 4, 1] = 140 + 30 * np.sin(t)
    return positions.astype(np.float32)


def arrays_file(frames: int, repetitions: int) -> bytes:
    patient = swinging_skeleton(frames, repetitions)
    buffer = io.BytesIO()
    np.savez_compressed(
        buffer, patient_positions=patient, tutor_positions=patient + 5, parents=PARENTS,
        joint_names=NAMES, landmark_frames=np.array([0], np.int32),
        landmark_types=np.array([1], np.int32),
    )  # fmt: skip
    return buffer.getvalue()


def summary(frames: int, fps: float, scores: list[float], knee: float) -> dict:
    length = frames // len(scores)
    return {
        "frames": frames, "fps": fps, "score": sum(scores) / len(scores), "landmarks": [],
        "repetitions": [
            {"start": i * length, "end": (i + 1) * length - 1, "peak": i * length + length // 2,
             "score": s, "passed": s >= 70}
            for i, s in enumerate(scores)
        ],
        "clinical_angles": {"knee_flexion_left": {"min": 0.0, "max": knee, "range": knee}},
    }  # fmt: skip


def stored(patient, exercise, *, frames: int, fps: float, scores, knee: float, days_ago: int):
    from django.utils import timezone

    recording = make_recording(patient, exercise)
    run = recording.runs.first()
    run.status = RunStatus.SUCCEEDED
    run.summary = summary(frames, fps, scores, knee)
    run.arrays.save("run.npz", ContentFile(arrays_file(frames, len(scores))), save=False)
    run.save()
    when = timezone.now() - datetime.timedelta(days=days_ago)
    Recording.objects.filter(pk=recording.pk).update(
        uploaded_at=when, n_frames=frames, fps=fps, duration_s=frames / fps
    )
    return recording


@pytest.fixture
def two_sessions(transactional_db, settings, tmp_path):
    settings.MEDIA_ROOT = tmp_path / "media"
    world = make_world()
    squat = make_exercise(world.clinic)
    first = stored(
        world.patient,
        squat,
        frames=300,
        fps=30.0,
        scores=[55.0, 60.0, 65.0],
        knee=80.0,
        days_ago=14,
    )
    latest = stored(
        world.patient, squat, frames=200, fps=25.0, scores=[80.0, 85.0, 90.0], knee=95.0, days_ago=1
    )
    return world, first, latest


def log_in(page, base_url: str) -> None:
    sign_in(page, base_url, "therapist", PASSWORD)


def seconds(page, side: str) -> float:
    text = page.inner_text(f".compare-viewer[data-side='{side}'] .time-label")
    return float(re.match(r"([\d.]+) s$", text).group(1))


def test_two_viewers_play_in_step(page, live_server, two_sessions):
    _, first, latest = two_sessions
    log_in(page, live_server.url)
    # The one-click way in: the latest recording's "compare with the first session".
    page.goto(f"{live_server.url}/recordings/{latest.pk}/")
    page.click("#compare-first a")
    page.wait_for_selector("#compare-playback[data-ready='1']")
    assert f"a={first.pk}" in page.url and f"b={latest.pk}" in page.url

    assert page.locator("#compare-playback canvas").count() == 2
    for canvas in page.locator("#compare-playback canvas").all():
        box = canvas.bounding_box()
        assert box["width"] > 200 and box["height"] > 200
    assert seconds(page, "a") == 0.0 and seconds(page, "b") == 0.0
    assert page.input_value("#compare-mode") == "repetition"  # both have repetitions

    page.click("#compare-play")
    page.wait_for_function(
        "document.querySelector(\".compare-viewer[data-side='b'] .time-label\").textContent"
        " !== '0.00 s'"
    )
    page.wait_for_timeout(1200)
    page.click("#compare-play")  # pause
    a, b = seconds(page, "a"), seconds(page, "b")
    assert a > 0.5 and b > 0.5
    # In step: both are the same fraction through the same repetition (each rep of A is 100
    # frames at 30 fps, 3.33 s; of B 66 frames at 25 fps, 2.64 s), within a frame or two.
    rep_length_a, rep_length_b = 99 / 30.0, 65 / 25.0
    assert a / rep_length_a == pytest.approx(b / rep_length_b, abs=0.05)
    assert page.inner_text(".compare-viewer[data-side='a'] .rep-label") == "repetition 1 of 3"
    assert page.inner_text(".compare-viewer[data-side='b'] .rep-label") == "repetition 1 of 3"

    # The one slider moves both: half way through the shared span is repetition 2 in each.
    page.select_option("#compare-mode", "time")
    page.eval_on_selector(
        "#compare-scrub", "s => { s.value = 500; s.dispatchEvent(new Event('input')); }"
    )
    assert seconds(page, "a") == pytest.approx(299 / 2 / 30.0, abs=0.05)
    assert seconds(page, "b") == pytest.approx(199 / 2 / 25.0, abs=0.05)


def test_no_horizontal_overflow_at_1280(page, live_server, two_sessions):
    world, first, latest = two_sessions
    log_in(page, live_server.url)
    page.set_viewport_size({"width": 1280, "height": 900})
    page.goto(f"{live_server.url}/patients/{world.patient.pk}/compare/?a={first.pk}&b={latest.pk}")
    page.wait_for_selector("#compare-playback[data-ready='1']")
    overflow = page.evaluate(
        "document.documentElement.scrollWidth - document.documentElement.clientWidth"
    )
    assert overflow <= 0
    assert "+15°" in page.inner_text("#compare-angles")  # 95 − 80
