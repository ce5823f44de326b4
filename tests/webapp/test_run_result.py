"""A run's stored summary is read through `AnalysisRun.result` (the pipeline's typed result), and
a recording's result comes from `Recording.latest_succeeded_run`, prefetched or not."""

from __future__ import annotations

from datetime import timedelta

import pytest
from django.db.models import Prefetch

from analysis.pipeline import AnalysisSummary
from tests.personas import make_exercise, make_recording
from webapp.exercises.models import ExerciseModel
from webapp.recordings.models import AnalysisRun, Recording, RunStatus

STORED = {
    "frames": 90,
    "fps": 30.0,
    "score": 71.5,
    "landmarks": [{"frame": 3, "type": 1}, {"frame": 40, "type": 2}],
    "repetitions": [{"start": 3, "end": 80, "score": 71.5, "guidance": "slow down"}],
    "gamma": {"Spine": 0.4},
    "a_field_of_a_newer_pipeline": [1, 2, 3],
}


@pytest.fixture
def recording(world):
    return make_recording(world.patient, make_exercise(world.clinic))


def test_result_is_the_typed_summary_and_follows_a_new_summary(recording):
    run = AnalysisRun.objects.create(recording=recording)
    assert run.result is None
    run.summary = STORED
    result = run.result
    assert isinstance(result, AnalysisSummary) and run.result is result  # parsed once
    assert result.score == 71.5 and result.repetition_count == 1
    assert result.repetitions[0].main_guidance == "slow down"
    assert [m.frame for m in result.landmarks] == [3, 40] and result.gamma == {"Spine": 0.4}
    run.summary = {**STORED, "score": 20.0}
    assert run.result.score == 20.0


def test_latest_succeeded_run_with_and_without_prefetched_runs(recording):
    old = AnalysisRun.objects.create(recording=recording, status=RunStatus.SUCCEEDED)
    newer = AnalysisRun.objects.create(recording=recording, status=RunStatus.SUCCEEDED)
    AnalysisRun.objects.create(recording=recording, status=RunStatus.FAILED)
    AnalysisRun.objects.filter(pk=old.pk).update(created_at=newer.created_at - timedelta(hours=1))
    assert recording.latest_succeeded_run() == newer
    listed = Recording.objects.prefetch_related(
        Prefetch("runs", queryset=AnalysisRun.objects.only("recording", "status", "created_at"))
    ).get(pk=recording.pk)
    assert listed.latest_succeeded_run() == newer


def test_model_versions_count_up_per_exercise(world):
    exercise = make_exercise(world.clinic)
    first = ExerciseModel.objects.create_next_version(exercise)
    second = ExerciseModel.objects.create_next_version(exercise, status="failed")
    assert (first.version, second.version, second.status) == (1, 2, "failed")
    other = ExerciseModel.objects.create_next_version(make_exercise(world.clinic, name="Other"))
    assert other.version == 1
