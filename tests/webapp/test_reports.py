"""Playback payload, report PDFs (task + downloads), printable pages and the progress page."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from django.core.files.base import ContentFile
from django.urls import reverse

from tests.personas import make_exercise, make_recording
from webapp.recordings.models import RunStatus

F, J = 40, 5
PARENTS = np.array([-1, 0, 1, 2, 1], dtype=np.int32)


def npz(with_tutor: bool) -> bytes:
    rng = np.random.default_rng(0)
    arrays = {
        "patient_positions": rng.normal(size=(F, J, 3)).astype(np.float32),
        "parents": PARENTS,
        "landmark_frames": np.array([3, 20, 35], dtype=np.int32),
        "landmark_types": np.array([1, 2, 1], dtype=np.int32),
        "joint_names": np.array(["Hips", "Spine", "Neck", "Head", "Arm"]),
    }
    if with_tutor:
        arrays["tutor_positions"] = arrays["patient_positions"] + 1
        arrays["tutor_adjusted_positions"] = arrays["patient_positions"] + 2
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    return buffer.getvalue()


SUMMARY = {
    "frames": F,
    "fps": 20.0,
    "score": 71.5,
    "landmarks": [{"frame": 3, "type": 1}, {"frame": 20, "type": 2}, {"frame": 35, "type": 1}],
    "repetitions": [{"start": 3, "end": 35, "peak": 20, "score": 71.5, "guidance": "slow down"}],
    "assessment": [{"frame": 20, "type": 2, "levels": {"Spine": 2}}],
    "feedback": [{"frame": 20, "text": "Bend your knees more.", "tip": "knees"}],
    "gamma": {"Spine": 0.4},
    "range_of_motion": {"Spine": 33.0},
}


def analysed(recording, with_tutor: bool = True):
    run = recording.runs.first()
    run.status = RunStatus.SUCCEEDED
    run.summary = SUMMARY
    run.arrays.save("run.npz", ContentFile(npz(with_tutor)), save=False)
    run.save()
    return run


@pytest.fixture
def recording(world):
    return make_recording(world.patient, make_exercise(world.clinic))


def test_playback_description_lists_present_skeletons_only(client, world, recording):
    analysed(recording)
    client.force_login(world.therapist)
    data = client.get(reverse("reports:playback", kwargs={"pk": recording.pk})).json()
    assert data["available"] is True
    assert (data["frames"], data["joints"], data["fps"]) == (F, J, 20.0)
    assert [s["key"] for s in data["skeletons"]] == ["patient", "tutor", "tutor_adjusted"]
    assert data["names"][1] == "Spine" and data["parents"] == PARENTS.tolist()
    assert [m["frame"] for m in data["landmarks"]] == [3, 20, 35]
    assert data["landmarks"][1]["name"] == "end of range"
    assert data["feedback"][0]["frame"] == 20
    # body segments' angles under their own name; no clinical curve kept in these arrays
    spine = [s for s in data["segments"]["series"] if s["joint"] == "Spine"]
    assert {s["skeleton"] for s in spine} == {"patient", "tutor_adjusted"}
    assert len(spine[0]["values"]) == len(data["segments"]["frames"]) == F
    assert data["angles"]["series"] == []


def test_playback_binary_is_float32_skeleton_frame_joint_xyz(client, world, recording):
    analysed(recording, with_tutor=False)
    client.force_login(world.patient_user)
    response = client.get(reverse("reports:playback-bin", kwargs={"pk": recording.pk}))
    assert response["Content-Type"] == "application/octet-stream"
    values = np.frombuffer(response.content, dtype="<f4").reshape(1, F, J, 3)
    run = recording.runs.first()
    with run.arrays.open("rb") as handle:
        expected = np.load(handle)["patient_positions"]
    np.testing.assert_array_equal(values[0], expected)


def test_playback_before_analysis_says_not_available(client, world, recording):
    client.force_login(world.therapist)
    data = client.get(reverse("reports:playback", kwargs={"pk": recording.pk})).json()
    assert data["available"] is False
    assert (
        client.get(reverse("reports:playback-bin", kwargs={"pk": recording.pk})).status_code == 409
    )


def test_recording_pdf_is_generated_by_the_task_after_commit(
    client, world, recording, django_capture_on_commit_callbacks
):
    analysed(recording)
    client.force_login(world.therapist)
    url = reverse("reports:recording-pdf", kwargs={"pk": recording.pk})
    with django_capture_on_commit_callbacks(execute=True) as callbacks:
        first = client.get(url)
    assert first.status_code == 202 and len(callbacks) == 1
    response = client.get(url)
    body = b"".join(response.streaming_content)
    assert response.status_code == 200 and body.startswith(b"%PDF")
    assert body.count(b"/Type /Page") >= 2  # the page tree plus at least one page


def test_task_renders_progress_report(world, recording, settings):
    from django.core.files.storage import default_storage

    from workers.tasks import make_report

    analysed(recording)
    name = make_report.delay("progress", str(world.patient.pk), "reports/p.pdf").get()
    with default_storage.open(name, "rb") as handle:
        assert handle.read(4) == b"%PDF"


def test_api_report_with_token(client, world, recording, django_capture_on_commit_callbacks):
    analysed(recording)
    from webapp.accounts.tokens import issue_token

    _, key = issue_token(world.therapist, "test")
    url = reverse("reports:api-recording-report", kwargs={"pk": recording.pk})
    headers = {"HTTP_AUTHORIZATION": f"Token {key}"}
    with django_capture_on_commit_callbacks(execute=True):
        assert client.get(url, **headers).status_code == 202
    response = client.get(url, **headers)
    assert response.status_code == 200
    assert b"".join(response.streaming_content).startswith(b"%PDF")
    _, outsider_key = issue_token(world.outsider, "test")
    assert client.get(url, HTTP_AUTHORIZATION=f"Token {outsider_key}").status_code == 404


def test_printable_pages_show_scores_and_feedback(client, world, recording):
    analysed(recording)
    client.force_login(world.therapist)
    page = client.get(reverse("reports:recording-print", kwargs={"pk": recording.pk}))
    assert b"Bend your knees more." in page.content and b"Score 72 / 100" in page.content
    page = client.get(reverse("reports:progress-print", kwargs={"pk": world.patient.pk}))
    assert b"Deep squat" in page.content


def test_recording_page_includes_viewer_when_analysed(client, world, recording):
    analysed(recording)
    client.force_login(world.therapist)
    page = client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).content.decode()
    assert 'id="viewer"' in page and "three.module.min.js" in page and "plotly.min.js" in page
    assert json.loads(page.split('type="importmap">')[1].split("</script>")[0])["imports"]["three"]


def test_joint_names_fall_back_to_the_tutor_skeleton(client, world, recording):
    from webapp.reports import playback

    run = analysed(recording)
    names = playback.tutor_joint_names(run)
    assert names[0] == "Waist" and len(names) > 10
    arrays = {"patient_positions": np.zeros((2, len(names), 3), np.float32)}
    assert playback.joint_names(run, arrays, len(names)) == names
    assert playback.joint_names(run, arrays, 3) == ["joint 0", "joint 1", "joint 2"]


def test_report_name_changes_with_a_new_run_and_period(world, recording):
    from datetime import date

    from webapp.recordings.models import AnalysisRun
    from webapp.reports import services

    analysed(recording)
    first = services.recording_report_name(recording)
    analysed_again = AnalysisRun.objects.create(recording=recording)  # queued: same report
    assert services.recording_report_name(recording) == first
    analysed_again.status = RunStatus.SUCCEEDED
    analysed_again.arrays.save("again.npz", ContentFile(npz(True)), save=False)
    analysed_again.save()
    assert services.recording_report_name(recording) != first
    whole = services.progress_report_name(world.patient, None, None)
    empty = services.progress_report_name(world.patient, date(2001, 1, 1), date(2001, 2, 1))
    assert whole != empty


def test_progress_page_lists_prescriptions_and_bad_dates_are_ignored(client, world, recording):
    from datetime import date

    from webapp.patients.models import Prescription

    analysed(recording)
    Prescription.objects.create(
        patient=world.patient, exercise=recording.exercise, start_date=date(2026, 1, 5)
    )
    client.force_login(world.therapist)
    page = client.get(reverse("reports:progress", kwargs={"pk": world.patient.pk}))
    assert b'"target_repetitions": 10' in page.content
    printable = reverse("reports:progress-print", kwargs={"pk": world.patient.pk})
    assert client.get(printable + "?since=not-a-date").status_code == 200
