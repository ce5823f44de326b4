"""The exercise's training report page: what the model learnt, in plain words."""

from __future__ import annotations

import json

import pytest
from django.urls import reverse
from django.utils import timezone

from tests.personas import make_exercise
from webapp.exercises.models import ExerciseModel, ModelStatus

REPORT = {
    "tutor_repetitions": 5,
    "labelled_repetitions": 12,
    "scorer": {"source": "labelled recordings", "joints": 21},
    "key_poses": {
        "classifier": "c45 + AdaBoost",
        "refining": "gap clustering, mu1 selection",
        "periodic_patterns": [[1, 2], [1, 2, 1]],
    },
    "joint_weights": [0.5, 1.75, 0.25],
    "alignment_error": {"before": 0.2143, "after": 0.0571},
    "pass_threshold": {"value": 70.0, "source": "labelled repetitions (Bayes, 001 eqs 13-15)"},
    "gesture_scale": 0.01234,
}


@pytest.fixture
def exercise(world):
    exercise = make_exercise(world.clinic)
    exercise.involved_joints = ["LeftUpLeg", "RightForeArm", "Spine1"]
    exercise.save()
    return exercise


def ready_model(exercise, report, version=1):
    return ExerciseModel.objects.create(
        exercise=exercise, version=version, status=ModelStatus.READY,
        training_report=report, finished_at=timezone.now(),
    )  # fmt: skip


def page(client, world, exercise, row) -> str:
    client.force_login(world.therapist)
    url = reverse("exercises:detail", kwargs={"pk": exercise.pk}) + f"?model={row.pk}"
    response = client.get(url)
    assert response.status_code == 200
    return response.content.decode()


def weights_of(html: str) -> list[dict]:
    return json.loads(
        html.split('id="joint-weights-data" type="application/json">')[1].split("<", 1)[0]
    )


def test_report_shows_every_part_in_plain_words(client, world, exercise):
    html = page(client, world, exercise, ready_model(exercise, REPORT))
    assert "a chain of yes/no questions about the body&#x27;s pose" in html
    assert "several of them voting together" in html
    assert "grouped wherever they are far apart in time" in html
    assert "start → end of range</li>" in html and "start → end of range → start" in html
    assert "A repetition passes with a score of <strong>70</strong>" in html
    assert "the same on every exercise" in html
    assert "set from labelled recordings" in html
    assert "21.4% with all joints weighted equally, 5.7% with the learnt joint weights" in html
    assert "trained on the therapist&#x27;s labelled recordings" in html
    assert "5 repetitions of the reference and 12 labelled repetitions" in html
    assert weights_of(html) == [
        {"name": "left thigh", "weight": 0.5},
        {"name": "right forearm", "weight": 1.75},
        {"name": "spine 1", "weight": 0.25},
    ]
    assert "plotly.min.js" in html and "training_report.js" in html
    for internal in (
        "c45",
        "C4.5",
        "AdaBoost",
        "decision tree",
        "boosted",
        "Candidate",
        "mu1",
        "LeftUpLeg",
        "gesture_scale",
        "periodic_patterns",
    ):
        assert internal not in html


def test_cold_start_threshold_says_it_comes_from_the_reference(client, world, exercise):
    report = {
        **REPORT,
        "pass_threshold": {"value": 70.0, "source": "tutor variation, on the one scale"},
        "scorer": {"source": "tutor repetitions", "joints": 21},
        "labelled_repetitions": 0,
    }
    html = page(client, world, exercise, ready_model(exercise, report))
    assert "set from the reference&#x27;s own variation" in html
    assert "without labelled recordings" in html
    assert "how much the reference&#x27;s own repetitions differ" in html


def test_older_models_show_what_they_have(client, world, exercise):
    old = {
        "tutor_repetitions": 4,
        "labelled_repetitions": 0,
        "scorer": {"source": "tutor repetitions", "joints": 20},
    }
    html = page(client, world, exercise, ready_model(exercise, old))
    assert "4 repetitions of the reference" in html and 'id="report-scorer"' in html
    for missing in (
        "report-key-poses",
        "report-threshold",
        "report-alignment",
        "joint-weights-chart",
    ):
        assert missing not in html
    html = page(client, world, exercise, ready_model(exercise, {}, version=2))
    assert "This model has no report." in html


def test_weights_without_joint_names_are_numbered(client, world, exercise):
    exercise.involved_joints = []
    exercise.save()
    html = page(client, world, exercise, ready_model(exercise, REPORT))
    assert [w["name"] for w in weights_of(html)] == ["joint 1", "joint 2", "joint 3"]


def test_exercise_page_shows_the_active_models_report_and_links_versions(client, world, exercise):
    older = ready_model(exercise, {"tutor_repetitions": 3})
    row = ready_model(exercise, REPORT, version=2)
    exercise.active_model = row
    exercise.save()
    client.force_login(world.therapist)
    url = reverse("exercises:detail", kwargs={"pk": exercise.pk})
    html = client.get(url).content.decode()
    assert "model version 2 (in use)" in html and "set from labelled recordings" in html
    assert f'href="?model={older.pk}#training-report"' in html
    html = client.get(f"{url}?model={older.pk}").content.decode()
    assert "model version 1</h2>" in html and "3 repetitions of the reference" in html


def test_without_a_ready_model_or_with_a_bad_id_no_report_is_shown(client, world, exercise):
    other = make_exercise(world.clinic, name="Lunge")
    foreign = ready_model(other, REPORT)
    client.force_login(world.therapist)
    url = reverse("exercises:detail", kwargs={"pk": exercise.pk})
    for query in ("", "?model=not-an-id", f"?model={foreign.pk}"):
        response = client.get(url + query)
        assert response.status_code == 200 and b'id="training-report"' not in response.content
