"""The clinic's confirmed takes reach the fit check (`webapp.recordings.similar.confirmed_takes`,
`workers.exercise_match.match_context`): a recording whose every repetition a therapist marked
"passed" represents its exercise besides the reference; a failed verdict, an unlabelled
repetition or a newer run (the recording moved or analysed again) leaves it out."""

from __future__ import annotations

import pytest

from tests.personas import make_exercise, make_recording
from webapp.recordings.models import AnalysisRun, RepetitionLabel
from webapp.recordings.similar import confirmed_takes
from workers.analysis_task import analyse_run
from workers.exercise_match import match_context


@pytest.fixture
def squat_take(world, monkeypatch):
    """A deep squat and a hurdle step; a squat recorded, analysed, fitting, not yet labelled."""
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda run_id: None)
    squat = make_exercise(world.clinic, "Deep squat", "reps/m01_s01_e01.bvh.gz")
    hurdle = make_exercise(world.clinic, "Hurdle step", "reps/m02_s01_e01.bvh.gz")
    recording = make_recording(world.patient, squat, source="reps/m01_s01_e02.bvh.gz")
    run = recording.runs.get()
    assert analyse_run(str(run.pk)) == "succeeded"
    run.refresh_from_db()
    assert run.summary["match"] == {"fits": True} and run.summary["repetitions"]
    return squat, hurdle, recording, run


def label(run: AnalysisRun, *verdicts: bool) -> None:
    for index, passed in enumerate(verdicts):
        RepetitionLabel.objects.create(run=run, index=index, passed=passed)


def test_a_take_with_every_repetition_passed_represents_its_exercise(squat_take):
    squat, hurdle, _, run = squat_take
    assert confirmed_takes(squat) == []  # no therapist's verdict yet
    label(run, *[True] * len(run.summary["repetitions"]))
    takes = confirmed_takes(squat)
    assert len(takes) == 1 and takes[0].ndim == 2 and takes[0].shape[1] == 17
    assert len(match_context(squat).own_takes) == 1
    (other,) = match_context(hurdle).candidates
    assert other.name.endswith("\u201cDeep squat\u201d") and len(other.takes) == 1
    assert match_context(hurdle).own_takes == ()


def test_a_failed_verdict_or_a_newer_run_leaves_the_take_out(squat_take):
    squat, _, recording, run = squat_take
    label(run, False, *[True] * (len(run.summary["repetitions"]) - 1))
    assert confirmed_takes(squat) == []
    RepetitionLabel.objects.filter(run=run).update(passed=True)
    assert len(confirmed_takes(squat)) == 1
    AnalysisRun.objects.create(recording=recording)  # moved or analysed again: queued
    assert confirmed_takes(squat) == []
