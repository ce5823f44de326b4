"""The exercise pages speak to therapists in plain words: the list, an exercise's page with its
model report, the new-exercise form, the change / replace / archive forms, the key-pose page and
the body parts it offers (each once, never a rig's joint name) for a demo exercise and for an
exercise whose reference comes from a CMU-style rig ("lowerneck", "LThumb", "LHipJoint")."""

from __future__ import annotations

import html
import re
from collections import Counter
from pathlib import Path

import pytest
from django.core.files.base import ContentFile
from django.urls import reverse

from analysis.bvh import read
from webapp.demo.clinic import DEMO_EXERCISES, ensure_exercise
from webapp.exercises import services
from webapp.exercises.models import Exercise

RIGS = Path(__file__).resolve().parents[2] / "data" / "rigs"
CMU_RIG = RIGS / "bvh11_131_01.bvh"
INTERNAL = (
    "C4.5",
    "AdaBoost",
    "decision tree",
    "boosted",
    "Tutor",
    "Landmark frames",
    "landmark_frames",
    "lowerneck",
    "left l ",
    "right r ",
    "candidate moments",
    "Candidate",
    "refining",
    "Order check",
    "GBDTW",
    "LeftUpLeg",
    "LHipJoint",
    "LThumb",
    "lhumerus",
    "0;41;72",
)


def visible_text(page: str) -> str:
    """What a reader sees: no scripts, styles or tags; entities decoded."""
    page = re.sub(r"<(script|style)\b.*?</\1>", " ", page, flags=re.S)
    return html.unescape(re.sub(r"<[^>]+>", " ", page))


def internal_words(text: str) -> list[str]:
    return [word for word in INTERNAL if word in text]


@pytest.fixture
def demo_exercise(world):
    exercise = ensure_exercise(world.clinic, DEMO_EXERCISES[0])
    services.build_model_now(exercise)
    exercise.refresh_from_db()
    return exercise


@pytest.fixture
def cmu_exercise(world):
    exercise = Exercise(clinic=world.clinic, name="Jumping jack")
    exercise.tutor_file.save("jack.bvh", ContentFile(CMU_RIG.read_bytes()), save=False)
    exercise.save()
    return exercise


def pages(exercise) -> list[str]:
    def url(name: str) -> str:
        return reverse(f"exercises:{name}", kwargs={"pk": exercise.pk})

    return [
        reverse("exercises:list"),
        reverse("exercises:list") + "?archived=1",
        reverse("exercises:create"),
        url("detail"),
        url("edit"),
        url("reference"),
        url("archive"),
        url("annotate"),
    ]


@pytest.mark.slow
def test_demo_exercise_pages_have_no_internal_words(client, world, demo_exercise):
    client.force_login(world.therapist)
    for path in pages(demo_exercise):
        answer = client.get(path)
        assert answer.status_code == 200, path
        found = internal_words(visible_text(answer.content.decode()))
        assert not found, f"{path}: {found}"
    detail = client.get(reverse("exercises:detail", kwargs={"pk": demo_exercise.pk}))
    text = visible_text(detail.content.decode())
    assert "Model report" in text and "Key poses are found by" in text


def test_new_exercise_form_has_a_heading_and_plain_labels(client, world):
    client.force_login(world.therapist)
    page = client.get(reverse("exercises:create")).content.decode()
    assert "<h1>New exercise</h1>" in page
    text = visible_text(page)
    assert "The reference" in text and "key poses" in text
    assert not internal_words(text)
    assert not re.search(r"\d+;\d+", text), "no frame-list syntax on the form"


def offered_labels(body: dict) -> list[str]:
    return [body["labels"][name] for name in body["body_parts"]]


def test_key_pose_page_offers_each_body_part_once_in_plain_words(client, world, cmu_exercise):
    client.force_login(world.therapist)
    path = reverse("exercises:tutor-data", kwargs={"pk": cmu_exercise.pk})
    body = client.get(path).json()
    labels = offered_labels(body)
    assert [n for n, c in Counter(labels).items() if c > 1] == []
    assert {"left thigh", "chest", "lower neck", "left thumb", "left hand"} <= set(labels)
    assert not internal_words(" | ".join(body["labels"].values()))
    shown = [body["labels"][name] for name in body["movement_order"]]
    assert len(shown) == len(set(shown)), "the body-part menu lists each part once"
    page = client.get(reverse("exercises:annotate", kwargs={"pk": cmu_exercise.pk}))
    assert page.status_code == 200
    assert not internal_words(visible_text(page.content.decode()))


def test_a_tick_on_left_thigh_is_the_thigh_and_reads_back_as_left_thigh(
    client, world, cmu_exercise
):
    client.force_login(world.therapist)
    data_url = reverse("exercises:tutor-data", kwargs={"pk": cmu_exercise.pk})
    body = client.get(data_url).json()
    thigh = next(n for n in body["body_parts"] if body["labels"][n] == "left thigh")
    skeleton = read(CMU_RIG.read_bytes()).skeleton
    index = skeleton.names.index(thigh)
    assert float(abs(skeleton.offsets[index]).sum()) > 0, "not a zero-length connector"
    answer = client.post(
        reverse("exercises:landmarks", kwargs={"pk": cmu_exercise.pk}),
        {"frames": "0;20", "types": "1;2", "involved_joints": f'["{thigh}"]'},
    )
    assert answer.status_code == 200, answer.content
    cmu_exercise.refresh_from_db()
    assert cmu_exercise.involved_joints == [thigh]
    back = client.get(data_url).json()
    assert [back["labels"][n] for n in back["involved_joints"]] == ["left thigh"]


def test_an_older_tick_on_a_connector_joint_shows_on_its_body_part(client, world, cmu_exercise):
    cmu_exercise.involved_joints = ["LHipJoint"]
    cmu_exercise.save()
    client.force_login(world.therapist)
    body = client.get(reverse("exercises:tutor-data", kwargs={"pk": cmu_exercise.pk})).json()
    assert [body["labels"][n] for n in body["involved_joints"]] == ["left thigh"]
    assert set(body["involved_joints"]) <= set(body["body_parts"])
