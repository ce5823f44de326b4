"""A phone video through MediaPipe Pose into the same analysis as any recording.

The squat video (two repetitions, side view; `fixtures/capture/README.md`) is read once per run:
about 20 s on one core.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from analysis.bvh import read
from analysis.pipeline import analyse, build_model
from analysis.sources import CaptureFileError, read_recording
from analysis.sources.pose_tracking import slices
from analysis.sources.video import landmarks_from_video, probe, read_video
from tests.analysis.fixtures.capture.make_squat_reference import (
    KEY_POSE_FRAMES,
    KEY_POSE_TYPES,
    REFERENCE,
    VIDEO,
)

FIXTURES = Path(__file__).parent / "fixtures" / "capture"


@pytest.fixture(scope="module")
def progress_seen() -> list[float]:
    return []


@pytest.fixture(scope="module")
def squat(progress_seen):
    return read_recording(VIDEO.name, VIDEO.read_bytes(), progress=progress_seen.append)


def test_the_video_header_is_read_without_decoding_it():
    header = probe(VIDEO)
    assert (header.width, header.height, header.frames) == (608, 1080, 614)
    assert header.fps == pytest.approx(29.97, abs=0.01)


def test_the_person_is_found_in_every_frame_and_the_source_is_named(squat, progress_seen):
    assert squat.report.kind == "video" and squat.source.kind == "video"
    assert squat.source.joints == 33  # MediaPipe's landmarks
    assert squat.motion.n_frames == 614
    assert squat.motion.fps == pytest.approx(29.97, abs=0.01)
    assert squat.report.warnings == ()  # nobody to bridge: found in all 614 frames
    assert progress_seen == sorted(progress_seen) and progress_seen[-1] > 0.9


def test_the_video_counts_its_two_squats_against_a_reference_made_from_it(squat):
    model = build_model(read(REFERENCE), list(KEY_POSE_FRAMES), list(KEY_POSE_TYPES))
    result = analyse(squat.motion, model).summary
    assert result.match.fits
    assert len(result.repetitions) == 2
    # the bottoms of the squats, near 10.2 s and 16.8 s of the video
    bottoms = sorted(r.peak / squat.motion.fps for r in result.repetitions)
    assert bottoms[0] == pytest.approx(10.2, abs=1.0) and bottoms[1] == pytest.approx(16.8, abs=1.0)
    knee = result.clinical_angles["knee_flexion_left"]
    assert 70 <= knee.max <= 150  # a deep barbell squat, in degrees


def test_the_reference_file_is_what_reading_the_video_gives(squat):
    """The committed reference must not drift from the video reader (fixture's docstring)."""
    reference = read(REFERENCE)
    assert reference.skeleton.names == squat.motion.skeleton.names  # depth first, as BVH lists
    rotations = [i for i, c in enumerate(sum(reference.skeleton.channels, ())) if "rotation" in c]
    difference = np.abs(reference.frames[:, rotations] - squat.motion.frames[:, rotations])
    assert np.median(difference) < 1.0  # degrees


def test_a_file_that_is_not_a_video_is_refused_in_words():
    with pytest.raises(CaptureFileError, match="cannot be read"):
        read_recording("squat.mp4", b"this text is not a video " * 100)


def test_a_video_without_a_person_is_refused_in_words(tmp_path):
    path = tmp_path / "empty_room.mp4"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (160, 120))
    for shade in range(45):
        writer.write(np.full((120, 160, 3), 40 + shade, dtype=np.uint8))
    writer.release()
    with pytest.raises(CaptureFileError, match=r"found in only 0 of 45 frames"):
        read_video(path)


def clip(path: Path, frames: range, fps: float) -> Path:
    """The squat video's ``frames`` at half size, written at ``fps`` without loss (FFV1): a
    frame reads back as the very picture written."""
    source = cv2.VideoCapture(str(VIDEO))
    source.set(cv2.CAP_PROP_POS_FRAMES, frames.start)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"FFV1"), fps, (304, 540))
    for index in range(frames.stop - frames.start):
        ok, frame = source.read()
        assert ok
        if index % frames.step == 0:
            writer.write(cv2.resize(frame, (304, 540), interpolation=cv2.INTER_AREA))
    writer.release()
    source.release()
    return path


def test_a_60_fps_video_is_read_at_30_frames_a_second(tmp_path):
    """Every other frame goes to MediaPipe: the landmarks of a 30 fps video of those frames."""
    path = clip(tmp_path / "60.mkv", range(240, 360), 59.94)
    sixty = landmarks_from_video(path, model="lite")
    assert sixty.step == 2 and sixty.world.shape[0] == 60 and sixty.found.all()
    assert sixty.fps == pytest.approx(29.97)
    thirty = clip(tmp_path / "30.mkv", range(240, 360, 2), 29.97)
    np.testing.assert_array_equal(sixty.world, landmarks_from_video(thirty, model="lite").world)
    recording = read_video(path, model="lite")  # the same 2 s, at the frames' rate
    assert recording.motion.n_frames == 60 and recording.motion.fps == pytest.approx(29.97)
    assert recording.report.layout.endswith("60 frames per second, analysed at 30")


def test_slices_of_a_video_read_every_other_frame_start_on_a_frame_that_is_read():
    for frames, workers in ((1800, 2), (1801, 3), (999, 4)):
        starts = [start for start, _ in slices(frames, workers, step=2)]
        assert starts[0] == 0 and all(start % 2 == 0 for start in starts)
        assert starts == sorted(set(starts)) and len(starts) == workers
