"""The tutor annotation data (joint-angle curves with key poses), saving edited key poses, and
live validation of the feedback grammar."""

from __future__ import annotations

import json

import pytest
from django.urls import reverse

from analysis.feedback import Grammar, default_grammar
from tests.personas import make_exercise
from webapp.exercises.annotate import kept_type_names
from webapp.exercises.annotate_data import grammar_names
from webapp.exercises.models import Exercise


@pytest.fixture
def exercise(world):
    return make_exercise(world.clinic)


def url(name: str, exercise) -> str:
    return reverse(f"exercises:{name}", kwargs={"pk": exercise.pk})


def test_tutor_data_has_angle_curves_and_key_poses(client, world, exercise):
    client.force_login(world.therapist)
    body = client.get(url("tutor-data", exercise)).json()
    assert body["n_frames"] == 73 and body["landmark_frames"] == [0, 41, 72]
    knee = next(j for j in body["joints"] if j == "LeftLowerLeg")
    curve = body["angles_deg"][knee]
    assert len(curve) == 73 and all(0 <= a <= 180 for a in curve)
    assert max(curve) - min(curve) > 20, "a squat bends the knee"


def test_tutor_data_suggests_rest_and_extreme_poses_near_the_labelled_ones(client, world, exercise):
    client.force_login(world.therapist)
    body = client.get(url("tutor-data", exercise)).json()
    assert body["suggested_types"] == [1, 2, 1]
    offsets = [abs(s - f) for s, f in zip(body["suggested_frames"], [0, 41, 72], strict=True)]
    assert max(offsets) <= 5, body["suggested_frames"]


def test_saving_key_poses(client, world, exercise):
    client.force_login(world.therapist)
    knee = next(
        j for j in client.get(url("tutor-data", exercise)).json()["joints"] if j == "LeftLowerLeg"
    )
    answer = client.post(
        url("landmarks", exercise),
        {
            "frames": "72;0;40",
            "types": "1;1;2",
            "type_names": json.dumps({"2": "deepest"}),
            "involved_joints": json.dumps([knee]),
        },
    )
    assert answer.status_code == 200, answer.content
    exercise.refresh_from_db()
    assert exercise.tutor_landmark_frames == [0, 40, 72]
    assert exercise.tutor_landmark_types == [1, 2, 1]
    # The posted name wins; kind 1 keeps the name it had.
    assert exercise.landmark_type_names == {"1": "start", "2": "deepest"}
    assert exercise.involved_joints == [knee]


@pytest.mark.parametrize(
    "case",
    [
        ({"frames": "0;500", "types": "1;2"}, "between 0 and 72"),
        ({"frames": "0;10", "types": "2;2"}, "type 1"),
        ({"frames": "0;x", "types": "1;2"}, "whole numbers"),
        ({"frames": "0;10", "types": "1;2", "involved_joints": '["Tail"]'}, "Unknown joints"),
    ],
)
def test_bad_key_poses_are_400(client, world, exercise, case):
    data, reason = case
    client.force_login(world.therapist)
    answer = client.post(url("landmarks", exercise), data)
    assert answer.status_code == 400 and reason in answer.content.decode()
    exercise.refresh_from_db()
    assert exercise.tutor_landmark_frames == [0, 41, 72]


def test_grammar_live_validation_and_save(client, world, exercise):
    client.force_login(world.therapist)
    good = default_grammar(["LeftLowerLeg"], {1: "start", 2: "end of range"})
    check = client.post(url("grammar", exercise), {"text": good}, content_type="application/json")
    assert check.json()["valid"] is True
    bad = good + "\nthis is ( not a rule"
    verdict = client.post(url("grammar", exercise), {"text": bad}, content_type="application/json")
    body = verdict.json()
    assert body["valid"] is False and body["line"] >= 2 and body["column"] >= 1 and body["message"]
    refused = client.post(
        url("grammar", exercise), {"text": bad, "save": True}, content_type="application/json"
    )
    assert refused.status_code == 400
    assert Exercise.objects.get(pk=exercise.pk).feedback_grammar == ""
    saved = client.post(
        url("grammar", exercise), {"text": good, "save": True}, content_type="application/json"
    )
    assert saved.json()["saved"] is True
    assert Exercise.objects.get(pk=exercise.pk).feedback_grammar == good


def test_annotation_page_links_its_data(client, world, exercise):
    client.force_login(world.therapist)
    page = client.get(url("annotate", exercise)).content.decode()
    assert url("tutor-data", exercise) in page and url("grammar", exercise) in page
    assert "js/annotate.js" in page
    detail = client.get(url("detail", exercise)).content.decode()
    assert url("annotate", exercise) in detail


def test_tutor_data_names_body_parts_orders_them_by_movement_and_has_the_pose(
    client, world, exercise
):
    client.force_login(world.therapist)
    body = client.get(url("tutor-data", exercise)).json()
    joints, labels = body["joints"], body["labels"]
    assert labels["LeftLowerLeg"] == "left lower leg" and labels["LeftUpperLeg"] == "left thigh"
    assert not set(labels.values()) & set(joints), "no rig joint name is shown"
    order = body["movement_order"]
    assert sorted(order) == sorted(joints) and order[-1] == joints[0], "the root comes last"
    spread = [max(body["angles_deg"][j]) - min(body["angles_deg"][j]) for j in order[:-1]]
    assert spread == sorted(spread, reverse=True) and spread[0] > 20
    pose = body["pose"]
    assert len(pose["parents"]) == len(joints) and pose["parents"][0] == -1
    assert len(pose["positions"]) == body["n_frames"] * len(joints) * 3


def test_kept_type_names():
    assert kept_type_names({"2": " deepest "}, {"1": "begin", "2": "old"}, [1, 2, 1]) == {
        "1": "begin",
        "2": "deepest",
    }
    # Kind 1 is "start" when nobody named it; other unnamed kinds stay unnamed.
    assert kept_type_names({}, {}, [1, 3]) == {"1": "start"}
    # A name typed for a kind with no key pose marked is not stored.
    assert kept_type_names({"5": "x"}, {}, [1]) == {"1": "start"}


def test_grammar_names_are_plain_unless_two_joints_read_the_same():
    names = grammar_names(("Hips", "LeftUpLeg", "LeftUpperLeg", "RightKnee"))
    assert names["RightKnee"] == "right_knee"
    assert names["LeftUpLeg"] == "LeftUpLeg" and names["LeftUpperLeg"] == "LeftUpperLeg"


def test_page_fills_the_default_grammar_until_one_is_saved(client, world, exercise):
    client.force_login(world.therapist)
    page = client.get(url("annotate", exercise))
    text = page.context["grammar"]
    assert page.context["grammar_is_default"] is True and Grammar.parse(text).rules
    assert "grammar-guide" in page.content.decode()
    joints = exercise.tutor_motion().skeleton.names
    assert not any(f"@{name}$" in text for name in joints), "body parts in plain words"
    Exercise.objects.filter(pk=exercise.pk).update(feedback_grammar='type$1 -> F:"Well done"')
    again = client.get(url("annotate", exercise))
    assert again.context["grammar"] == 'type$1 -> F:"Well done"'
    assert again.context["grammar_is_default"] is False


def test_grammar_check_refuses_unknown_body_parts_and_key_pose_types(client, world, exercise):
    """Issue 25: `@banana$3` and `type$9` answered "Valid" and never fired."""
    client.force_login(world.therapist)
    for rule, words, known in [
        ('type$2 & @banana$3 -> F:"Peel it"', "no body part 'banana'", "left_"),
        ('type$9 -> F:"Never said"', "no key-pose type 9", "1 (start)"),
    ]:
        text = 'type$1 -> F:"Ready"\n' + rule + "\n"
        answer = client.post(
            url("grammar", exercise), {"text": text}, content_type="application/json"
        )
        verdict = answer.json()
        assert verdict["valid"] is False and verdict["line"] == 2
        assert words in verdict["message"] and known in verdict["message"]
