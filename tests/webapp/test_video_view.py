"""The recording page's phone video (`webapp/recordings/video_views.py`): served only to those who
may see the recording, with its content type, and in byte ranges so a browser can seek in it."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import pytest
from django.core.files.base import ContentFile
from django.template.loader import render_to_string
from django.urls import reverse

from tests.personas import make_exercise, make_recording
from webapp.recordings.models import Recording

VIDEO = Path(__file__).resolve().parents[1] / "analysis/fixtures/capture/side_squat_2reps.mp4"


@pytest.fixture
def content() -> bytes:
    return VIDEO.read_bytes()


@pytest.fixture
def video_recording(world, content) -> Recording:
    recording = Recording(
        clinic=world.clinic,
        patient=world.patient,
        exercise=make_exercise(world.clinic),
        checksum=hashlib.sha256(content).hexdigest(),
        original_name="squats.mp4",
        size_bytes=len(content),
    )
    recording.file.save(f"{recording.pk}.mp4", ContentFile(content), save=False)
    recording.save()
    return recording


def url(recording: Recording) -> str:
    return reverse("recordings:video", args=[recording.pk])


def body(response) -> bytes:
    return b"".join(response.streaming_content)


@pytest.mark.parametrize("who", ["therapist", "colleague", "patient_user"])
def test_those_who_see_the_recording_get_the_whole_video(client, world, video_recording, content,
                                                         who):  # fmt: skip
    client.force_login(getattr(world, who))
    response = client.get(url(video_recording))
    assert response.status_code == 200
    assert response["Content-Type"] == "video/mp4"
    assert response["Accept-Ranges"] == "bytes"
    assert int(response["Content-Length"]) == len(content)
    assert body(response) == content


@pytest.mark.parametrize("who", ["outsider", "other_patient_user"])
def test_another_clinic_or_another_patient_gets_404(client, world, video_recording, who):
    client.force_login(getattr(world, who))
    assert client.get(url(video_recording)).status_code == 404


def test_anonymous_visitors_are_sent_to_log_in(client, video_recording):
    response = client.get(url(video_recording))
    assert response.status_code == 302
    assert "/accounts/login" in response["Location"]


def test_a_range_request_answers_206_with_exactly_those_bytes(client, world, video_recording,
                                                             content):  # fmt: skip
    client.force_login(world.therapist)
    response = client.get(url(video_recording), HTTP_RANGE="bytes=1000-1999")
    assert response.status_code == 206
    assert response["Content-Range"] == f"bytes 1000-1999/{len(content)}"
    assert response["Content-Length"] == "1000"
    assert response["Content-Type"] == "video/mp4"
    assert body(response) == content[1000:2000]


def test_open_ended_and_suffix_ranges(client, world, video_recording, content):
    client.force_login(world.therapist)
    start = len(content) - 700
    tail = client.get(url(video_recording), HTTP_RANGE=f"bytes={start}-")
    assert tail.status_code == 206
    assert body(tail) == content[start:]
    last = client.get(url(video_recording), HTTP_RANGE="bytes=-300")
    assert last["Content-Range"] == f"bytes {len(content) - 300}-{len(content) - 1}/{len(content)}"
    assert body(last) == content[-300:]


def test_a_range_past_the_end_answers_416(client, world, video_recording, content):
    client.force_login(world.therapist)
    response = client.get(url(video_recording), HTTP_RANGE=f"bytes={len(content) + 5}-")
    assert response.status_code == 416
    assert response["Content-Range"] == f"bytes */{len(content)}"


def test_a_recording_that_is_not_a_video_has_none(client, world):
    recording = make_recording(world.patient, make_exercise(world.clinic))
    client.force_login(world.therapist)
    assert client.get(url(recording)).status_code == 404


def test_the_player_shows_a_muted_labelled_video_only_for_a_video(world, video_recording):
    page = render_to_string("recordings/viewer.html", {"recording": video_recording, "run": None})
    video = re.search(r"<video [^>]*>", page)
    assert video, page
    assert f'src="{url(video_recording)}"' in video.group(0)
    assert " muted" in video.group(0) and "autoplay" not in video.group(0)
    label = re.search(r'aria-labelledby="([^"]+)"', video.group(0))
    assert label and f'id="{label.group(1)}"' in page
    bvh = make_recording(world.patient, video_recording.exercise)
    assert "<video" not in render_to_string(
        "recordings/viewer.html", {"recording": bvh, "run": None}
    )
