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
from analysis.sources.video import probe, read_video
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
