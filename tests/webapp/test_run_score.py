"""The run's `score` column follows `summary["score"]` on every way a run is written."""

from __future__ import annotations

import pytest

from tests.personas import make_exercise, make_recording
from webapp.recordings.models import AnalysisRun, RunStatus


@pytest.fixture
def recording(world):
    return make_recording(world.patient, make_exercise(world.clinic))


def test_save_update_and_bulk_create_keep_the_score_column(recording):
    run = AnalysisRun.objects.create(recording=recording, summary={"score": 71.5})
    assert AnalysisRun.objects.get(pk=run.pk).score == 71.5

    AnalysisRun.objects.filter(pk=run.pk).update(summary={"score": 40})
    assert AnalysisRun.objects.get(pk=run.pk).score == 40.0

    run.refresh_from_db()
    run.summary = {"repetitions": []}
    run.save(update_fields=["summary"])
    assert AnalysisRun.objects.get(pk=run.pk).score is None

    made = AnalysisRun.objects.bulk_create(
        [
            AnalysisRun(recording=recording, status=RunStatus.SUCCEEDED, summary={"score": s})
            for s in (10, 90)
        ]
    )
    assert sorted(
        AnalysisRun.objects.filter(pk__in=[r.pk for r in made]).values_list("score", flat=True)
    ) == [10.0, 90.0]


def test_a_score_that_is_not_a_number_is_no_score(recording):
    run = AnalysisRun.objects.create(recording=recording, summary={"score": "n/a"})
    assert AnalysisRun.objects.get(pk=run.pk).score is None
