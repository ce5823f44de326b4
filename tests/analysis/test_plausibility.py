"""The plausibility check every analysis runs first (`analysis.bvh.plausibility`): a damaged
header, an over-long take or an analysis too big for memory is refused in plain words before
anything is resampled; durations are never rounded into contradictions."""

from __future__ import annotations

import gzip
import re
from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import ImplausibleRecordingError, Limits, RecordingTooShortError, check_recording
from analysis.bvh import read as read_bvh
from analysis.bvh.plausibility import analysis_bytes, distinct_durations, duration_text
from analysis.pipeline.prepare import check_length
from tests.analysis import bvh_cases as bc

ROOT = Path(__file__).resolve().parents[2]
REP = ROOT / "data/ui-prmd/reps/m07_s01_e01.bvh.gz"


def with_frame_time(text: str, frame_time: str) -> str:
    return re.sub(r"Frame Time:.*", f"Frame Time: {frame_time}", text)


@pytest.fixture(scope="module")
def rep_text() -> str:
    return gzip.decompress(REP.read_bytes()).decode()


def test_a_real_recording_passes(rep_text):
    check_recording(read_bvh(rep_text), 30.0, 22)


@pytest.mark.parametrize("frame_time", ["1000", "1", "0.5", "0.0001", "1e-9"])
def test_a_frame_time_no_capture_system_produces_is_refused(rep_text, frame_time):
    motion = read_bvh(with_frame_time(rep_text, frame_time))
    with pytest.raises(ImplausibleRecordingError) as caught:
        check_recording(motion, 30.0, 22)
    message = str(caught.value)
    assert f"each frame lasts {float(frame_time):g} s" in message
    assert "between 10 and 1000 frames per second" in message
    assert "Export the recording again" in message


@pytest.mark.parametrize("frame_time", ["0.001", "0.1", "0.033333", "0.0083333", "0.041667"])
def test_frame_times_of_real_capture_systems_pass(rep_text, frame_time):
    check_recording(read_bvh(with_frame_time(rep_text, frame_time)), 30.0, 22)


def test_too_many_frames_is_refused_with_the_maximum(rep_text):
    motion = read_bvh(rep_text)
    with pytest.raises(ImplausibleRecordingError, match=r"at most 50 can be analysed"):
        check_recording(motion, limits=Limits(max_frames=50))


def test_too_long_is_refused_with_both_durations_distinct(rep_text):
    motion = read_bvh(rep_text)
    limit = motion.duration - 0.01
    with pytest.raises(ImplausibleRecordingError) as caught:
        check_recording(motion, limits=Limits(max_seconds=limit))
    lasts, most = re.search(r"lasts ([\d.]+ s); at most ([\d.]+ s)", str(caught.value)).groups()
    assert lasts != most


def test_huge_or_nan_values_are_refused_with_the_frame():
    motion = read_bvh(bc.SMALL)
    frames = motion.frames.copy()
    frames[1, 4] = 1e300
    with pytest.raises(ImplausibleRecordingError, match=r"frame 2 has 1e\+300"):
        check_recording(motion.with_frames(frames))
    frames[1, 4] = np.nan
    with pytest.raises(ImplausibleRecordingError, match="frame 2"):
        check_recording(motion.with_frames(frames))


def test_the_memory_estimate_follows_the_models_frame_rate(rep_text):
    motion = read_bvh(rep_text)
    at_30, at_300 = analysis_bytes(motion, 30.0, 22), analysis_bytes(motion, 300.0, 22)
    resampled_30 = at_300 - at_30  # only the resampled part grows with the rate
    assert resampled_30 == pytest.approx(9 * (at_30 - analysis_bytes(motion, 0.0, 22)), rel=0.05)
    with pytest.raises(ImplausibleRecordingError, match=r"would need about \d+ MB of memory"):
        check_recording(motion, 30.0, 22, Limits(max_analysis_bytes=at_30 - 1))
    check_recording(motion, 30.0, 22, Limits(max_analysis_bytes=at_30))


def test_a_frame_time_of_1000_is_refused_before_resampling(rep_text):
    """The issue's file: a 63-frame take becomes 1.9 million frames at 30 fps (26 GB)."""
    motion = read_bvh(with_frame_time(rep_text, "1000"))
    assert analysis_bytes(motion, 30.0, 22) > 10 * (2 << 30)
    with pytest.raises(ImplausibleRecordingError, match="frame time is wrong"):
        check_recording(motion, 30.0, 22)


def test_limits_come_from_settings_with_defaults():
    class Settings:
        RECORDING_MAX_SECONDS = 60
        RECORDING_MAX_FRAMES = 1000

    limits = Limits.from_settings(Settings())
    assert (limits.max_seconds, limits.max_frames) == (60.0, 1000)
    assert limits.max_analysis_bytes == Limits().max_analysis_bytes


@pytest.mark.parametrize(
    ("a", "b"), [(0.6333, 0.6499), (0.61, 0.64), (0.6001, 0.6004), (59.96, 59.99), (1800.4, 1800)]
)
def test_two_different_durations_never_print_the_same(a, b):
    first, second = distinct_durations(a, b)
    assert first != second


def test_durations_read_as_people_say_them():
    assert duration_text(0.6) == "0.6 s"
    assert duration_text(125) == "2 min 5 s"
    assert duration_text(120) == "2 min"
    assert duration_text(3 * 3600 + 120) == "3 h 2 min"


def test_the_too_short_message_does_not_contradict_itself(rep_text):
    """19 frames at 30 fps (0.63 s) against a 0.65 s bar: today's '0.6 s ... at least 0.6 s'."""
    motion = read_bvh(rep_text)
    short = motion.with_frames(motion.frames[:19])
    with pytest.raises(RecordingTooShortError) as caught:
        check_length(short, rep_frames=39.0, model_fps=30.0)
    lasts, least = re.search(r"lasts ([\d.]+ s) .* at least ([\d.]+ s)", str(caught.value)).groups()
    assert lasts != least
    assert float(lasts[:-2]) < float(least[:-2])


def test_a_file_without_frames_is_refused(rep_text):
    head = rep_text.split("Frames:")[0]
    motion = read_bvh(head + "Frames: 0\nFrame Time: 0.033333\n")
    with pytest.raises(ImplausibleRecordingError, match=r"no movement \(0 frames\)"):
        check_recording(motion, 30.0, 22)
