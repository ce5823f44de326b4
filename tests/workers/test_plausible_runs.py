"""Issue 25: the worker refuses an implausible recording with its plain reason before the
pipeline allocates anything (a `Frame Time: 1000` file once grew a worker to 22 GB)."""

from __future__ import annotations

import gzip
import hashlib
import re

import pytest
from django.core.files.base import ContentFile

from tests.personas import fixture_bytes, make_exercise, make_world
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from workers import analysis_task


def recording_with(world, exercise, content: bytes) -> Recording:
    recording = Recording(
        clinic=world.clinic, patient=world.patient, exercise=exercise,
        checksum=hashlib.sha256(content).hexdigest(),
    )  # fmt: skip
    recording.file.save("rec.bvh", ContentFile(content), save=False)
    recording.save()
    AnalysisRun.objects.create(recording=recording)
    return recording


@pytest.fixture
def world(db):
    return make_world()


def absurd() -> bytes:
    text = gzip.decompress(fixture_bytes("reps/m01_s01_e02.bvh.gz")).decode()
    return re.sub(r"Frame Time:.*", "Frame Time: 1000", text).encode()


def test_a_frame_time_of_1000_fails_the_run_with_the_reason_before_the_pipeline(world, monkeypatch):
    recording = recording_with(world, make_exercise(world.clinic), absurd())
    run = AnalysisRun.objects.get(recording=recording)

    def never(*args, **kwargs):
        raise AssertionError("the pipeline must not start on this recording")

    monkeypatch.setattr(analysis_task, "analyse", never)
    assert analysis_task.analyse_run(str(run.pk)) == "failed"
    run.refresh_from_db()
    assert run.status == RunStatus.FAILED
    assert run.user_error.startswith("The file says each frame lasts 1000 s")
    assert run.user_error != analysis_task.GENERIC_FAILURE


def test_the_sites_limits_reach_the_worker(world, settings):
    settings.RECORDING_MAX_FRAMES = 20
    recording = recording_with(
        world,
        make_exercise(world.clinic),
        gzip.decompress(fixture_bytes("reps/m01_s01_e02.bvh.gz")),
    )
    run = AnalysisRun.objects.get(recording=recording)
    assert analysis_task.analyse_run(str(run.pk)) == "failed"
    run.refresh_from_db()
    assert "at most 20 can be analysed" in run.user_error
