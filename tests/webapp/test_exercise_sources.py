"""An exercise's reference (tutor) from any capture source on the web (issue 27): the exercise
form and the replace-reference form accept every file `analysis.sources.read_recording` reads,
store it under its real ending, read it back through the same entry point, and the exercise page
says what it was measured with; a file no importer can read is refused in the importer's words.
A model built from a Kinect reference analyses a BVH recording."""

from __future__ import annotations

import gzip
from pathlib import Path

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.urls import reverse

from analysis.bvh import read
from tests.capture_samples import canonical_points, kinect_wide_csv, trc
from tests.personas import fixture_bytes, fixture_landmarks, make_exercise, make_recording
from tests.webapp.test_replace_reference import confirm_key_poses
from webapp.exercises.models import Exercise, ExerciseModel, ModelStatus
from webapp.recordings import similar
from workers.analysis_task import analyse_run

TUTOR = "reps/m01_s01_e01.bvh.gz"  # the UI-PRMD deep squat the persona exercises use
VIDEO = Path(__file__).resolve().parents[1] / "analysis/fixtures/capture/side_squat_2reps.mp4"


def tutor_as(writer) -> bytes:
    """The tutor's joint positions written as another capture source's file."""
    motion = read(gzip.decompress(fixture_bytes(TUTOR)))
    return writer(canonical_points(motion), motion.fps)


def create(client, name: str, filename: str, content: bytes):
    frames, types = fixture_landmarks(TUTOR)
    data = {
        "name": name,
        "description": "Squat down and up.",
        "tutor": SimpleUploadedFile(filename, content),
        "landmark_frames": ";".join(map(str, frames)),
        "landmark_types": ";".join(map(str, types)),
    }
    return client.post(reverse("exercises:create"), data)


def create_without_key_poses(client, name: str, filename: str, content: bytes):
    """As a therapist does: the key poses are marked (or checked) on the next page."""
    data = {"name": name, "tutor": SimpleUploadedFile(filename, content)}
    return client.post(reverse("exercises:create"), data)


def detail(client, exercise: Exercise) -> str:
    return client.get(reverse("exercises:detail", kwargs={"pk": exercise.pk})).content.decode()


@pytest.mark.parametrize(
    "source",
    [
        ("pose2sim.trc", trc, "trc", "marker or keypoint positions (.trc)"),
        ("kinect.csv", kinect_wide_csv, "kinect", "a depth camera (Kinect)"),
    ],
)
def test_an_exercise_is_created_from_another_capture_source(client, world, source):
    filename, writer, kind, words = source
    client.force_login(world.therapist)
    response = create(client, "Squat", filename, tutor_as(writer))
    assert response.status_code == 302, response.content.decode()[:3000]
    exercise = Exercise.objects.get(name="Squat")
    assert exercise.tutor_file.name.endswith(filename[filename.rindex(".") :])
    assert exercise.tutor_kind() == kind
    motion = Exercise.objects.get(pk=exercise.pk).tutor_motion()  # read back from storage
    assert motion.n_frames == read(gzip.decompress(fixture_bytes(TUTOR))).n_frames
    page = detail(client, exercise)
    assert f"Measured from {words}" in page
    assert 'id="reference-canvas"' in page  # read at once: no video to wait for
    body = client.get(reverse("exercises:reference-data", kwargs={"pk": exercise.pk})).json()
    assert body["n_frames"] == motion.n_frames


def test_the_exercise_page_of_a_bvh_reference_says_so(client, world):
    exercise = make_exercise(world.clinic)
    client.force_login(world.therapist)
    assert "Measured from a motion-capture file (BVH)" in detail(client, exercise)


@pytest.mark.parametrize(
    ("filename", "content", "words"),
    [
        ("steps.csv", b"date,steps\n2024-01-01,4000\n2024-01-02,5200\n", "not a readable"),
        ("head.csv", b"Time,Head_X,Head_Y,Head_Z\n0,0,1.6,0\n0.1,0,1.6,0\n", "no usable"),
        ("notes.trc", b"PathFileType\t4\t(X/Y/Z)\tnotes.trc\n", "not a readable"),
        ("scan.pdf", b"%PDF-1.4 not motion at all", "another capture file"),
    ],
)
def test_a_file_no_importer_reads_is_refused_in_words(client, world, filename, content, words):
    client.force_login(world.therapist)
    response = create(client, "Squat", filename, content)
    assert response.status_code == 400
    assert words in response.content.decode()
    assert not Exercise.objects.filter(name="Squat").exists()


@pytest.mark.slow
def test_a_kinect_reference_builds_a_model_that_analyses_a_bvh_recording(
    client, world, django_capture_on_commit_callbacks
):
    exercise = make_exercise(world.clinic)
    client.force_login(world.therapist)
    with django_capture_on_commit_callbacks(execute=True):  # the model build, in-process
        response = client.post(
            reverse("exercises:reference", kwargs={"pk": exercise.pk}),
            {"tutor": SimpleUploadedFile("kinect.csv", tutor_as(kinect_wide_csv))},
        )
    assert response.status_code == 302, response.content.decode()[:3000]
    confirm_key_poses(client, exercise, django_capture_on_commit_callbacks)  # builds the model
    exercise.refresh_from_db()
    assert exercise.tutor_file.name.endswith(".csv")
    built = exercise.models.get()
    assert built.status == ModelStatus.READY, built.error
    assert exercise.active_model_id == built.pk
    recording = make_recording(world.patient, exercise, source="reps/m01_s01_e02.bvh.gz")
    assert analyse_run(str(recording.runs.get().pk)) == "succeeded"
    run = recording.runs.get()
    assert run.model_id == built.pk
    assert run.result.repetitions
    assert run.result.score is not None


@pytest.mark.slow
def test_a_phone_video_reference_is_read_by_the_model_build_not_the_page(
    client, world, django_capture_on_commit_callbacks
):
    client.force_login(world.therapist)
    with django_capture_on_commit_callbacks(execute=False) as queued:
        response = create_without_key_poses(client, "Back squat", VIDEO.name, VIDEO.read_bytes())
    assert response.status_code == 302, response.content.decode()[:3000]
    exercise = Exercise.objects.get(name="Back squat")
    assert exercise.tutor_file.name.endswith(".mp4") and exercise.tutor_kind() == "video"
    assert exercise.models.get().status == ModelStatus.QUEUED
    # until the worker has read it, the pages do not run the pose estimator themselves
    assert not exercise.tutor_ready()
    page = detail(client, exercise)
    assert 'id="reference-reading"' in page and 'id="reference-canvas"' not in page
    data_url = reverse("exercises:reference-data", kwargs={"pk": exercise.pk})
    assert client.get(data_url).status_code == 409
    annotate = client.get(reverse("exercises:annotate", kwargs={"pk": exercise.pk}))
    assert annotate.status_code == 409 and "still being read" in annotate.content.decode()
    assert similar.exercise_features(exercise) is None  # recognition leaves it out meanwhile

    for callback in queued:  # the worker's model build (eager): reads the video, then fits
        callback()
    exercise.refresh_from_db()
    built = exercise.models.get()
    assert built.status == ModelStatus.READY, built.error
    assert exercise.tutor_ready()
    assert len(exercise.tutor_landmark_frames) >= 2 and 1 in exercise.tutor_landmark_types
    page = detail(client, exercise)
    assert "Measured from a phone video" in page and 'id="reference-canvas"' in page
    assert client.get(reverse("exercises:annotate", kwargs={"pk": exercise.pk})).status_code == 200
    assert similar.exercise_features(exercise).shape[1] > 0
    body = client.get(data_url).json()
    assert body["n_frames"] == 614 and body["fps"] == pytest.approx(30.0, abs=0.5)


def test_reading_a_reference_video_moves_the_progress_of_its_running_build(world):
    exercise = make_exercise(world.clinic)
    done = ExerciseModel.objects.create_next_version(exercise, status=ModelStatus.READY)
    running = ExerciseModel.objects.create_next_version(exercise, status=ModelStatus.RUNNING)
    exercise.reading(0.5)  # half the video's frames read
    running.refresh_from_db()
    done.refresh_from_db()
    assert running.progress == 40 and done.progress == 0
