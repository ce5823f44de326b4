"""The recording page's timeline and repetition table, and their print forms."""

from __future__ import annotations

import pytest
from django.urls import reverse

from tests.personas import make_exercise, make_recording
from tests.webapp.test_reports import npz
from webapp.recordings.models import RunStatus
from webapp.reports import content, pdf

SUMMARY = {
    "frames": 40, "fps": 20.0, "score": 55.0, "segmentation": "fallback", "pass_threshold": 50.0,
    "landmarks": [
        {"frame": 3, "type": 1, "origin": "identified"},
        {"frame": 20, "type": 2, "origin": "refined"},
        {"frame": 35, "type": 1, "origin": "inserted"},
    ],
    "periodic": {"candidates": 7, "removed": [12], "inserted": [35]},
    "repetitions": [
        {"start": 3, "end": 20, "peak": 10, "score": 74.0, "passed": True,
         "guidance": [{"type": "too fast", "frames": [4, 10]}]},
        {"start": 20, "end": 35, "peak": 28, "score": 31.0, "passed": False,
         "guidance": [{"type": "overdone", "frames": [22, 30]},
                      {"type": "incomplete", "frames": [31, 34]}]},
    ],
}  # fmt: skip


@pytest.fixture
def recording(world):
    from django.core.files.base import ContentFile

    recording = make_recording(world.patient, make_exercise(world.clinic))
    run = recording.runs.first()
    run.status = RunStatus.SUCCEEDED
    run.summary = SUMMARY
    run.arrays.save("run.npz", ContentFile(npz(True)), save=False)
    run.save()
    return recording


def test_page_draws_layers_guidance_and_verdicts_in_seconds(client, world, recording):
    client.force_login(world.therapist)
    html = client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).content.decode()
    for layer in ("identified", "refined", "periodic"):
        assert f'<input type="checkbox" data-layer="{layer}" checked>' in html
        assert f'class="tl-row layer" data-layer="{layer}"' in html
    assert "key poses recognised directly: 1" in html
    assert "key poses adjusted to the nearest clear position: 1" in html
    assert "key poses removed (1) or added (1) so they come in the exercise's order" in html
    assert '<span style="left:51.282%">1</span>' in html and "time (s)" in html
    assert 'class="landmark identified type-1" data-frame="3"' in html
    assert 'class="landmark refined type-2" data-frame="20"' in html
    assert 'class="removed" data-frame="12"' in html
    assert 'class="landmark inserted type-1" data-frame="35"' in html
    assert html.count('class="guidance"') == 3
    assert ">too fast</div>" in html and ">went too far</div>" in html
    assert ">did not reach far enough</div>" in html
    assert "passed (score 74, needs 50)" in html and "not passed (score 31, needs 50)" in html
    assert "too fast (0.2–0.5 s)" in html and "<td>0.2–1.0</td>" in html
    assert html.lower().count("the key poses did not form a repeating cycle") == 1
    for internal in ("overdone", "incomplete", "fallback</", "origin"):
        assert internal not in html


def test_older_runs_have_no_fallback_note_and_are_judged_by_score(client, world, recording):
    run = recording.runs.first()
    run.summary = {
        "frames": 40, "fps": 20.0, "score": 40.0, "landmarks": [{"frame": 3, "type": 1}],
        "repetitions": [{"start": 3, "end": 35, "score": 40.0, "guidance": "too slow"}],
    }  # fmt: skip
    run.save()
    client.force_login(world.therapist)
    html = client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).content.decode()
    assert "not passed (score 40, needs 50)" in html and ">too slow</div>" in html
    assert "repeating cycle" not in html


def test_pdf_and_printable_page_hold_the_repetition_table_and_timeline(client, world, recording):
    report = content.recording_content(recording)
    assert report["repetitions"][1] == [
        2, "1.0–1.8", 31, "not passed (score 31, needs 50)",
        "went too far (1.1–1.5 s); did not reach far enough (1.6–1.7 s)",
    ]  # fmt: skip
    assert report["timeline"]["fallback"] and len(report["timeline"]["removed"]) == 1
    body = pdf.recording_pdf(report)
    assert body.startswith(b"%PDF")
    drawing = pdf.timeline_drawing(report["timeline"])
    texts = [s.text for s in drawing.contents if hasattr(s, "text")]
    assert "time (s)" in texts and "#1 pass 74" in texts and "Exercise's order" in texts
    assert "Key poses found" in texts and "Adjusted key poses" in texts
    client.force_login(world.therapist)
    page = client.get(reverse("reports:recording-print", kwargs={"pk": recording.pk}))
    assert b"passed (score 74, needs 50)" in page.content and b"Time (s)" in page.content


def test_stage_label_is_shown_while_running_only(client, world, recording):
    run = recording.runs.first()
    run.status, run.stage = RunStatus.RUNNING, "finding key poses"
    run.save()
    client.force_login(world.therapist)
    html = client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).content.decode()
    assert '<span id="run-stage" class="muted">· finding key poses</span>' in html
    run.status, run.stage = RunStatus.SUCCEEDED, "done"
    run.save()
    html = client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).content.decode()
    assert '<span id="run-stage" class="muted"></span>' in html
