"""The camera page's server side: MediaPipe world landmarks (what the browser's pose engine finds
in the phone video of two squats, `fixtures/`) turned into the exercise skeleton's frames, the
live session counting them, and the landmarks saved as a MediaPipe file the offline reader reads
back frame for frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import read
from analysis.live import LiveSession
from analysis.live.camera import VALUES_PER_FRAME, CameraFrameError, CameraStream, landmarks_of
from analysis.pipeline import build_model
from analysis.sources import read_recording
from tests.analysis.fixtures.capture import make_squat_reference as squat

LANDMARKS = Path(__file__).parent / "fixtures" / "side_squat_world_landmarks.npz"


@pytest.fixture(scope="module")
def squat_model():
    """The back squat made from the same video (its key poses as the capture tests use them)."""
    reference = read(squat.REFERENCE)
    return build_model(reference, list(squat.KEY_POSE_FRAMES), list(squat.KEY_POSE_TYPES))


def camera_values() -> tuple[np.ndarray, float]:
    """(frames, 132) values as the browser sends them, every landmark visible, and the rate."""
    data = np.load(LANDMARKS)
    world = data["world"].astype(np.float64)
    seen = np.ones((*world.shape[:2], 1))
    return np.concatenate([world, seen], axis=2).reshape(len(world), -1), float(data["fps"])


def test_hidden_landmarks_are_missing_and_wrong_sizes_refused():
    values, _ = camera_values()
    frame = values[:1].copy()
    frame[0, 4 * 25 + 3] = 0.2  # the left knee barely visible
    world = landmarks_of(frame)
    assert np.isnan(world[0, 25]).all() and np.isfinite(world[0, 26]).all()
    with pytest.raises(CameraFrameError):
        landmarks_of(values[:1, :-1])
    with pytest.raises(CameraFrameError):
        landmarks_of(values[:1] * 100.0)  # centimetres are not metres


def test_no_skeleton_before_the_whole_body_is_seen(squat_model):
    values, fps = camera_values()
    stream = CameraStream(fps, squat_model.tutor.skeleton)
    hidden = values[:3].copy()
    hidden[:, 4 * 27 + 3] = 0.0  # an ankle out of the picture
    assert stream.header(hidden) is None
    with pytest.raises(CameraFrameError):
        stream.channels(values[:3])
    assert stream.header(values[:3]) is not None


def test_two_squats_counted_live_and_saved_as_landmarks(squat_model):
    values, fps = camera_values()
    stream = CameraStream(fps, squat_model.tutor.skeleton)
    session = LiveSession(squat_model)
    assert session.handle({"type": "start", "header": stream.header(values[:1])})[0]["event"] == (
        "ready"
    )
    events = []
    for first in range(0, len(values), 4):  # batches as the page sends them
        block = values[first : first + 4]
        events += session.take_batch(first, stream.channels(block))
        stream.keep(block)
    events += session.end()
    assert [e for e in events if e["event"] == "error"] == []
    repetitions = [e for e in events if e["event"] == "repetition"]
    assert len(repetitions) == 2 and all(e["words"] for e in repetitions)
    assert events[-1]["repetitions"] == 2

    imported = read_recording("camera.json", stream.recording_json())
    assert imported.report.kind == "camera"  # the result says where it came from
    assert imported.motion.n_frames == len(values) == session.next_seq
    assert imported.motion.frame_time == pytest.approx(1.0 / fps)


def test_frame_rate_bounds(squat_model):
    with pytest.raises(CameraFrameError):
        CameraStream(0.0, squat_model.tutor.skeleton)
    assert VALUES_PER_FRAME == 132
