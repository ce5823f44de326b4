"""Uploading capture files other than BVH (issue 27): the page and the API accept a Pose2Sim-style
``.trc`` and a Kinect joint-position ``.csv``; the file is stored with its real ending, the worker
reads it through the same entry point (`analysis.sources.read_recording`) and the result names
its ``source``; a CSV that holds no joint positions is refused in words."""

from __future__ import annotations

import gzip
from pathlib import Path

import pytest
from django.core.exceptions import ValidationError
from django.core.files.uploadedfile import SimpleUploadedFile
from django.urls import reverse
from rest_framework.test import APIClient

from analysis.bvh import read
from tests.capture_samples import canonical_points, kinect_wide_csv, trc
from tests.personas import fixture_bytes, make_exercise
from webapp.recordings.models import AnalysisRun, Recording
from webapp.recordings.uploads import parse_upload

SOURCE = "reps/m01_s01_e02.bvh.gz"  # a repetition of the exercise's own tutor's rig


@pytest.fixture
def exercise(world):
    return make_exercise(world.clinic)


def positions_as(writer) -> bytes:
    motion = read(gzip.decompress(fixture_bytes(SOURCE)))
    return writer(canonical_points(motion), motion.fps)


def test_the_api_accepts_a_trc_and_the_result_names_its_source(
    world, exercise, django_capture_on_commit_callbacks
):
    api = APIClient()
    api.force_authenticate(world.therapist)
    content = positions_as(trc)
    markers = [n for n in content.split(b"\n")[3].split(b"\t")[2:] if n.strip()]
    data = {
        "patient": str(world.patient.pk),
        "exercise": str(exercise.pk),
        "file": SimpleUploadedFile("session.trc", content),
    }
    with django_capture_on_commit_callbacks(execute=True):  # the analysis, in-process (eager)
        created = api.post("/api/v1/recordings/", data, format="multipart")
    assert created.status_code == 201, created.content
    detail = api.get(f"/api/v1/recordings/{created.json()['id']}/").json()
    assert detail["status"] == "succeeded", detail
    assert detail["result"]["source"] == {"kind": "trc", "joints": len(markers)}
    assert detail["result"]["repetitions"]
    assert Recording.objects.get().file.name.endswith(".trc")


def test_the_upload_page_accepts_a_kinect_csv(
    client, world, exercise, django_capture_on_commit_callbacks
):
    client.force_login(world.therapist)
    content = positions_as(kinect_wide_csv)
    joints = {c.rsplit(b"_", 1)[0] for c in content.split(b"\n")[0].split(b",")[1:]}
    data = {
        "patient": str(world.patient.pk),
        "exercise": str(exercise.pk),
        "file": SimpleUploadedFile("kinect.csv", content),
    }
    with django_capture_on_commit_callbacks(execute=True):
        response = client.post(reverse("recordings:upload"), data)
    assert response.status_code == 302, response.content[:2000]
    run = AnalysisRun.objects.get()
    run.refresh_from_db()
    assert run.status == "succeeded"
    assert run.result.source.kind == "kinect"
    assert run.result.source.joints == len(joints)
    assert Recording.objects.get().file.name.endswith(".csv")


@pytest.mark.parametrize(
    ("content", "words"),
    [
        (b"date,steps\n2024-01-01,4000\n2024-01-02,5200\n", "not a readable capture file"),
        (b"Time,Head_X,Head_Y,Head_Z\n0,0,1.6,0\n0.1,0,1.6,0\n", "no usable positions"),
    ],
)
def test_a_junk_csv_is_refused_in_words(client, world, exercise, content, words):
    client.force_login(world.therapist)
    data = {
        "patient": str(world.patient.pk),
        "exercise": str(exercise.pk),
        "file": SimpleUploadedFile("junk.csv", content),
    }
    response = client.post(reverse("recordings:upload"), data)
    assert response.status_code == 400
    assert words in response.content.decode()
    assert Recording.objects.count() == 0


def test_an_exercise_tutor_stays_bvh_only():
    """Tutors are stored and read back as BVH, so only patients' recordings take other sources."""
    content = positions_as(trc)
    with pytest.raises(ValidationError, match="Upload a BVH"):
        parse_upload(SimpleUploadedFile("tutor.trc", content))
    assert parse_upload(SimpleUploadedFile("take.trc", content), any_source=True).kind == "trc"


KERAAL = Path(__file__).resolve().parents[1] / "analysis" / "fixtures" / "keraal"


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("G3-Kinect-CTK-P1T1-Unknown-C-0.txt", "kinect"),
        ("G3-Vicon-CTK-P1T1-Unknown-C-0.txt", "vicon"),
    ],
)
def test_the_api_accepts_a_recorders_own_text_file(
    world, exercise, django_capture_on_commit_callbacks, name, kind
):
    """Files a Kinect and a Vicon system wrote themselves (KERAAL), under their own `.txt`."""
    api = APIClient()
    api.force_authenticate(world.therapist)
    data = {
        "patient": str(world.patient.pk),
        "exercise": str(exercise.pk),
        "file": SimpleUploadedFile(name, (KERAAL / name).read_bytes()),
    }
    with django_capture_on_commit_callbacks(execute=True):
        created = api.post("/api/v1/recordings/", data, format="multipart")
    assert created.status_code == 201, created.content
    detail = api.get(f"/api/v1/recordings/{created.json()['id']}/").json()
    assert detail["status"] == "succeeded", detail
    assert detail["result"]["source"]["kind"] == kind
    assert Recording.objects.get().file.name.endswith(".txt")
