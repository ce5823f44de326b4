"""Phone videos counted against references made from UI-PRMD BVH files of the same exercise
(issue 35 item 5, issue 36): the Kinect deep squat of the demo clinic counts the two squats of the
side-view video, whatever frames a camera gives; the standing pauses between them are no
repetitions, nor is the lifter racking the bar at the end of the take.

The videos and their landmarks are in `fixtures/capture/` (provenance and licences in its README;
`make_video_landmarks.py` says how the landmarks were made); the UI-PRMD exercises are made as the
demo clinic makes them, and camera sessions as the browser's pose engine would take the frames
(`tests/video_cases.py`; `bench/eval_videos.py` prints the same counts). The counting tests
start from the landmarks; one test reads the squat video itself (about 20 s) and checks that it
still gives them.
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.bvh import Motion
from analysis.landmarks import suggest_key_poses
from analysis.landmarks.segmentation import fuse_peaks
from analysis.pipeline import FittedModel, analyse, build_model
from analysis.pipeline.match import Candidate, MatchContext, features_of
from analysis.sources import read_recording
from tests.video_cases import (
    CAPTURE,
    CLIP_SLOWER,
    camera_recording,
    page_recording,
    stored_landmarks,
    ui_prmd_model,
    upload_motion,
)

SQUAT, BALANCE = "side_squat_2reps.mp4", "pose2sim_balancing_cam01.mp4"
BOTTOMS_S = (10.2, 16.8)  # the squats' bottoms in the video (fixtures/capture/README.md)


@pytest.fixture(scope="module")
def deep_squat() -> FittedModel:
    return ui_prmd_model("m01")


def camera_session(video: str, rate: float, shift: float) -> Motion:
    world, _, fps = stored_landmarks(video)
    return camera_recording(world, fps, rate, shift)


def bottoms_s(motion: Motion, model: FittedModel) -> list[float]:
    """The seconds at which each counted repetition reaches its end of range."""
    summary = analyse(motion, model).summary
    assert summary.match.fits
    return [r.peak / summary.fps for r in summary.repetitions]


def test_the_squat_video_counts_its_two_squats_against_the_kinect_deep_squat(deep_squat):
    found = bottoms_s(upload_motion(SQUAT), deep_squat)
    assert len(found) == 2, found  # the standing pauses before and between are no squats
    assert found == pytest.approx(BOTTOMS_S, abs=1.0)


@pytest.mark.parametrize(("rate", "shift"), [(10.5, 0.0), (12.0, 0.5), (15.0, 0.0), (20.0, 0.5)])
def test_a_camera_session_of_the_squats_counts_two_whatever_frames_it_took(deep_squat, rate, shift):
    found = bottoms_s(camera_session(SQUAT, rate, shift), deep_squat)
    assert len(found) == 2, found  # nor the bar's racking at the end
    assert found == pytest.approx(BOTTOMS_S, abs=1.0)


@pytest.mark.parametrize(("engine_rate", "seed"), [(3.0, 0), (6.0, 0)])
def test_the_camera_page_on_the_browser_tests_clip_counts_two(deep_squat, engine_rate, seed):
    """As `tests/e2e/test_camera_page.py` records it: a few pose results a second of a slowed
    clip, interpolated to the page's steady rate; the take ends with the bar racked."""
    world, _, fps = stored_landmarks(SQUAT)
    found = bottoms_s(page_recording(world, fps, engine_rate, seed), deep_squat)
    assert len(found) == 2, found
    assert np.divide(found, CLIP_SLOWER) == pytest.approx(BOTTOMS_S, abs=1.0)


def test_the_single_leg_balance_counts_once_against_the_kinect_hurdle_step():
    """UI-PRMD has no balancing exercise; its hurdle step is the one standing on one leg while the
    other moves away and back (the straight-leg raise counts the same, `bench/eval_videos.py`)."""
    hurdle_step = ui_prmd_model("m02")
    assert len(bottoms_s(upload_motion(BALANCE), hurdle_step)) == 1
    trc = CAPTURE / "pose2sim_balancing.trc"  # the same movement, triangulated from four views
    assert len(bottoms_s(read_recording(trc.name, trc.read_bytes()).motion, hurdle_step)) == 1


def test_key_poses_suggested_on_the_squat_video_leave_out_the_racking():
    motion = upload_motion(SQUAT)
    suggested = suggest_key_poses(motion)
    extremes = suggested.frames[suggested.types == 2] / motion.fps
    assert extremes.tolist() == pytest.approx(BOTTOMS_S, abs=1.0)
    assert suggested.types.tolist() == [1, 2, 1, 2, 1]


def test_a_video_reference_with_the_suggested_key_poses_counts_two_squats():
    motion = upload_motion(SQUAT)
    suggested = suggest_key_poses(motion)
    reference = build_model(motion, suggested.frames.tolist(), suggested.types.tolist())
    assert len(bottoms_s(camera_session(SQUAT, 15.0, 0.0), reference)) == 2


def rest_and_humps(humps: list[tuple[float, int]], rest: int = 90) -> tuple[np.ndarray, np.ndarray]:
    """A progress signal: rests with a little wobble and one raised-cosine hump per (height,
    frames); and the frames of the humps' tops."""
    wobble = 0.02 * np.sin(np.arange(rest) / 5.0)
    parts, tops = [wobble], []
    for height, frames in humps:
        tops.append(sum(p.size for p in parts) + (frames - 1) // 2)
        parts += [height * 0.5 * (1 - np.cos(np.linspace(0, 2 * np.pi, frames))), wobble]
    return np.concatenate(parts), np.array(tops)


def test_a_key_pose_in_a_still_rest_adds_no_repetition():
    # two still stretches, then two repetitions; the classifier's ends of range in all four
    height, tops = rest_and_humps([(0.0, 60), (0.0, 60), (1.0, 60), (1.0, 60)])
    assert fuse_peaks(height, tops, rep_frames=60.0).tolist() == tops[2:].tolist()


def test_a_small_repetition_the_axis_missed_is_still_added_from_its_key_pose():
    # the third, short and shallow (as UI-PRMD m08 s05's), is no clear peak on the axis
    humps = [(1.0, 60), (1.0, 60), (0.11, 30), (1.0, 60), (1.0, 60), (1.0, 60), (1.0, 60)]
    height, tops = rest_and_humps(humps)
    assert fuse_peaks(height, tops, rep_frames=60.0).tolist() == tops.tolist()


def test_reading_the_squat_video_gives_the_stored_landmarks_and_two_squats(deep_squat):
    video = CAPTURE / SQUAT
    recording = read_recording(video.name, video.read_bytes())
    assert recording.motion.n_frames == stored_landmarks(SQUAT)[0].shape[0]
    stored = upload_motion(SQUAT)
    rotations = np.abs(recording.motion.frames[:, 3:] - stored.frames[:, 3:])
    assert np.median(rotations) < 1.0  # degrees: the stored landmarks are what the video gives
    assert len(bottoms_s(recording.motion, deep_squat)) == 2


def test_the_squats_fit_the_squat_beside_the_demo_clinics_other_exercises(deep_squat):
    """The fit check compares the recording with every exercise of the clinic (the demo's sit to
    stand and shoulder abduction here): a phone's landmarks against Kinect references are held
    to the margin for another recorder, so the squats are squats, counted twice, on upload and
    from the camera page alike."""
    others = tuple(
        Candidate(code, name, features_of(ui_prmd_model(code).tutor))
        for code, name in (("m05", "sit to stand"), ("m07", "shoulder abduction"))
    )
    context = MatchContext("the deep squat", others, same_recorder=False)
    world, _, fps = stored_landmarks(SQUAT)
    for motion in (upload_motion(SQUAT), page_recording(world, fps, 3.0, 0)):
        summary = analyse(motion, deep_squat, match=context).summary
        assert summary.match.fits, summary.match.message
        assert len(summary.repetitions) == 2
