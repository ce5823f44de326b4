"""The worker judges a session's pace against the patient's latest earlier session of the same
exercise (issue 26, item 4): the median tempo and excursion of its repetitions; nothing for a
first session, a deleted one, one of another exercise, or one that did not fit its exercise."""

from __future__ import annotations

from datetime import timedelta

import pytest
from django.utils import timezone

from analysis.pipeline.gestures import Pace
from analysis.pipeline.results import AnalysisSummary, ExerciseMatch, RepetitionResult
from tests.personas import make_exercise, make_recording, make_world
from webapp.live import services
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from workers.analysis_task import earlier_pace


def _summary(paces: list[tuple[float, float]], fits: bool = True) -> dict:
    reps = tuple(
        RepetitionResult(start=40 * k, end=40 * k + 30, peak=40 * k + 15, score=80.0,
                         tempo=tempo, excursion=excursion)
        for k, (tempo, excursion) in enumerate(paces)
    )  # fmt: skip
    match = ExerciseMatch() if fits else ExerciseMatch(False, "does not look like it")
    summary = AnalysisSummary(frames=200, fps=30.0, landmarks=(), repetitions=reps,
                              score=80.0 if fits else None, match=match)  # fmt: skip
    return summary.to_json()


def _analysed(recording: Recording, days_ago: int, summary: dict) -> None:
    Recording.all_objects.filter(pk=recording.pk).update(
        uploaded_at=timezone.now() - timedelta(days=days_ago)
    )
    AnalysisRun.objects.filter(recording=recording).update(
        status=RunStatus.SUCCEEDED, summary=summary
    )


@pytest.fixture
def world(db):
    world = make_world()
    return world, make_exercise(world.clinic)


def test_a_first_session_has_no_earlier_pace(world):
    world, exercise = world
    assert earlier_pace(make_recording(world.patient, exercise)) is None


def test_the_latest_earlier_session_gives_the_median_pace(world):
    world, exercise = world
    oldest, earlier = (
        make_recording(world.patient, exercise),
        make_recording(world.patient, exercise),
    )
    _analysed(oldest, 9, _summary([(2.0, 2.0)] * 3))
    _analysed(earlier, 5, _summary([(1.2, 0.9), (1.4, 1.1), (1.3, 1.0)]))
    now = make_recording(world.patient, exercise)
    assert earlier_pace(now) == Pace(1.3, 1.0, earlier=True)
    # another exercise's sessions, or a recording deleted since, say nothing about this one
    other = make_recording(world.patient, make_exercise(world.clinic, name="Shoulder raise"))
    assert earlier_pace(other) is None
    Recording.all_objects.filter(pk=earlier.pk).update(deleted_at=timezone.now())
    assert earlier_pace(Recording.objects.get(pk=now.pk)) == Pace(2.0, 2.0, earlier=True)


def test_an_earlier_session_that_did_not_fit_or_has_no_excursion_is_not_used(world):
    world, exercise = world
    earlier = make_recording(world.patient, exercise)
    _analysed(earlier, 3, _summary([], fits=False))
    assert earlier_pace(make_recording(world.patient, exercise)) is None
    stored = _summary([(1.0, 1.0)])
    for rep in stored["repetitions"]:
        del rep["excursion"]  # analysed before the excursion was stored
    AnalysisRun.objects.filter(recording=earlier).update(summary=stored)
    assert earlier_pace(make_recording(world.patient, exercise)) is None


def test_a_live_session_is_judged_against_the_pace_its_saved_analysis_will_use(world):
    """Live words and the saved session's page come from one judgement only if both read the
    same usual pace: the live session's options take it from the sessions before it, and a
    replay from the sessions before the replayed recording."""
    world, exercise = world
    earlier = make_recording(world.patient, exercise)
    _analysed(earlier, 5, _summary([(1.6, 1.0), (1.5, 1.0), (1.7, 1.0)]))
    live = services.create_session(patient=world.patient, exercise=exercise, user=world.therapist)
    own = services.session_options(live).own_pace
    assert own == Pace(1.6, 1.0, earlier=True)
    saved = make_recording(world.patient, exercise)  # what the session stores when it ends
    assert earlier_pace(saved) == own
    replay = services.create_session(
        patient=world.patient,
        exercise=exercise,
        user=world.therapist,
        replay_of=Recording.objects.get(pk=earlier.pk),
    )
    assert services.session_options(replay).own_pace is None  # nothing before the replayed one
