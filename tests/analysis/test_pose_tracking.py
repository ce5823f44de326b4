"""A video read one slice per core gives what reading it in one go gives (analysis.sources.
pose_tracking), with the lite landmark model the project ships and never a download.

A 3 s cut of the squat fixture keeps the file fast: about 5 s of MediaPipe on one core.
"""

from __future__ import annotations

import threading
from pathlib import Path

import cv2
import numpy as np
import pytest

from analysis.sources import pose_tracking
from analysis.sources.pose_tracking import pose_model, slices, track_slices
from tests.analysis.fixtures.capture.make_squat_reference import VIDEO

FRAMES = 90


@pytest.fixture(scope="module")
def short_video(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The squat fixture's frames 240–329 (standing into the first descent), as an mp4."""
    path = tmp_path_factory.mktemp("video") / "squat_cut.mp4"
    source = cv2.VideoCapture(str(VIDEO))
    source.set(cv2.CAP_PROP_POS_FRAMES, 240)
    writer = None
    for _ in range(FRAMES):
        ok, frame = source.read()
        assert ok
        if writer is None:
            size = (frame.shape[1], frame.shape[0])
            writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, size)
        writer.write(frame)
    assert writer is not None
    writer.release()
    source.release()
    return path


def test_slices_cover_the_video_in_order_and_short_videos_stay_whole():
    assert slices(1800, workers=2) == [(0, 900), (900, None)]
    assert slices(1800, workers=3) == [(0, 600), (600, 1200), (1200, None)]
    assert slices(200, workers=2) == [(0, None)]  # too short to pay for a second tracker
    assert slices(0, workers=4) == [(0, None)]  # unknown frame count: one slice, to the end


def test_the_lite_model_is_installed_from_the_repository_not_downloaded():
    assert pose_tracking.LITE_MODEL.is_file()
    assert pose_model("lite") == "lite"
    _, pose = pose_tracking.libraries()
    installed = Path(pose.__file__).resolve().parents[2] / "modules" / "pose_landmark"
    copy = installed / pose_tracking.LITE_MODEL.name
    assert copy.read_bytes() == pose_tracking.LITE_MODEL.read_bytes()
    assert pose_model("full") == "full"
    with pytest.raises(ValueError, match="lite"):
        pose_model("heavy")


def test_two_slices_give_the_landmarks_of_one_pass(short_video, monkeypatch):
    whole_world, whole_picture, whole_found = track_slices(
        str(short_video), FRAMES, "lite", None, workers=1
    )
    monkeypatch.setattr(pose_tracking, "MIN_SLICE", 30)
    calls: list[tuple[float, str]] = []

    def progress(share: float) -> None:
        calls.append((share, threading.current_thread().name))

    world, picture, found = track_slices(str(short_video), FRAMES, "lite", progress, workers=2)
    assert world.shape == whole_world.shape == (FRAMES, 33, 3)
    assert found.all() and whole_found.all()
    # MediaPipe is deterministic: the first slice is the one pass's first half, exactly.
    np.testing.assert_array_equal(world[:45], whole_world[:45])
    # The second slice's tracker warmed up on the 30 frames before it: the same body within
    # millimetres (tracking carries its history, so not bit for bit), not a cold start.
    gap_mm = 1000 * np.linalg.norm(world[45:] - whole_world[45:], axis=-1)
    assert np.median(gap_mm) < 15.0
    picture_gap = np.abs(picture[45:, :, :2] - whole_picture[45:, :, :2])  # share of the picture
    assert np.percentile(picture_gap, 95) < 0.01
    # Progress is reported from the caller's thread only (a database write in the worker).
    assert calls and {name for _, name in calls} == {threading.current_thread().name}
    assert [s for s, _ in calls] == sorted(s for s, _ in calls)
