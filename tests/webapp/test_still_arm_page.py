"""Issue 26: a recording whose trained arm stays down "does not look like the exercise" (no
repetition, no score) and the recording page and report still say what to correct."""

from __future__ import annotations

import hashlib

from django.core.files.base import ContentFile
from django.urls import reverse

from analysis.bvh import dumps, read
from tests.analysis.mistake_cases import arm_down
from tests.personas import FIXTURES, make_exercise
from webapp.recordings.models import AnalysisRun, Recording
from webapp.reports.content import recording_content
from workers.analysis_task import analyse_run


def test_an_arm_left_down_is_told_to_raise_it_on_the_page(client, world):
    arms = make_exercise(world.clinic, "Shoulder abduction", "reps/m07_s01_e01.bvh.gz")
    still = arm_down(read(FIXTURES / "reps/m07_s01_e02.bvh.gz"), "Right")
    content = dumps(still).encode()
    recording = Recording(clinic=world.clinic, patient=world.patient, exercise=arms,
                          checksum=hashlib.sha256(content).hexdigest())  # fmt: skip
    recording.file.save("rec.bvh", ContentFile(content), save=False)
    recording.save()
    AnalysisRun.objects.create(recording=recording)
    assert analyse_run(str(recording.runs.get().pk)) == "succeeded"
    run = recording.runs.get()
    assert run.summary["match"]["fits"] is False and run.score is None
    client.force_login(world.therapist)
    page = client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).content.decode()
    assert 'id="does-not-fit"' in page and "To correct" in page
    assert "Raise your right arm higher, by about" in page and "in the whole recording" in page
    report = recording_content(recording)
    assert report["feedback"][0] == run.summary["match"]["message"]
    assert any(line.startswith("Raise your right arm") for line in report["feedback"][1:])
