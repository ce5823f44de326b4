"""Replacing an exercise's reference through its page: the new recording's key poses are
suggested from that recording (never the frames marked on the old one), the version in use
stays in use, and a new version is built (and put in use) only once the therapist saves the
key poses. No upload is ever scored with a model built from the old recording's frames."""

from __future__ import annotations

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.urls import reverse

from tests.personas import fixture_bytes, make_exercise, make_recording
from webapp.exercises.models import Exercise, ModelStatus
from webapp.exercises.services import build_model_now
from workers.analysis_task import analyse_run
from workers.exercise_models import load_row

NEW_REFERENCE = "sessions/m01_s02_correct.bvh.gz"  # ten squats: the old frames "fit" its length


def confirm_key_poses(client, exercise: Exercise, execute) -> dict:
    """Save the key poses the page suggests, as the therapist does on the key-pose page."""
    data = client.get(reverse("exercises:tutor-data", kwargs={"pk": exercise.pk})).json()
    with execute(execute=True):  # the model build the save starts, in this process
        saved = client.post(
            reverse("exercises:landmarks", kwargs={"pk": exercise.pk}),
            {
                "frames": ";".join(map(str, data["suggested_frames"])),
                "types": ";".join(map(str, data["suggested_types"])),
                "type_names": "{}",
                "involved_joints": "[]",
            },
        )
    assert saved.status_code == 200, saved.content.decode()
    return saved.json()


@pytest.mark.slow
def test_a_replaced_reference_scores_nothing_with_the_old_frames(
    client, world, django_capture_on_commit_callbacks
):
    exercise = make_exercise(world.clinic)
    first = build_model_now(exercise)
    old_frames = list(exercise.tutor_landmark_frames)
    client.force_login(world.therapist)
    with django_capture_on_commit_callbacks(execute=True):
        response = client.post(
            reverse("exercises:reference", kwargs={"pk": exercise.pk}),
            {"tutor": SimpleUploadedFile("new.bvh.gz", fixture_bytes(NEW_REFERENCE))},
            follow=True,
        )
    page = response.content.decode()
    assert "model version 1 stays in use" in page and 'id="confirm-key-poses"' in page
    exercise.refresh_from_db()
    assert exercise.active_model_id == first.pk and exercise.models.count() == 1
    data = client.get(reverse("exercises:tutor-data", kwargs={"pk": exercise.pk})).json()
    assert data["landmark_frames"] == data["suggested_frames"] != old_frames
    build = client.post(reverse("exercises:build", kwargs={"pk": exercise.pk}), follow=True)
    assert "Check and save the new reference&#x27;s key poses first" in build.content.decode()
    waiting = make_recording(world.patient, exercise)
    assert analyse_run(str(waiting.runs.get().pk)) == "succeeded"
    assert waiting.runs.get().model_id == first.pk  # the version in use until confirmed

    saved = confirm_key_poses(client, exercise, django_capture_on_commit_callbacks)
    assert "Model version 2 is being built" in saved["message"]
    exercise.refresh_from_db()
    second = exercise.active_model
    assert second.version == 2 and second.status == ModelStatus.READY, second.error
    assert load_row(second).key_poses.frames.tolist() == data["suggested_frames"]
    detail = client.get(reverse("exercises:detail", kwargs={"pk": exercise.pk})).content.decode()
    assert 'id="confirm-key-poses"' not in detail
    after = make_recording(world.patient, exercise, source="reps/m01_s01_e02.bvh.gz")
    assert analyse_run(str(after.runs.get().pk)) == "succeeded"
    assert after.runs.get().model_id == second.pk
    for row in exercise.models.exclude(pk=first.pk):
        assert load_row(row).key_poses.frames.tolist() != old_frames
