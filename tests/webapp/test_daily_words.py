"""What a clinic's staff and a patient read on the pages of an ordinary day (issue 38), checked
in the page text: the login of a deactivated account, a duplicate feedback rule, the audit
log's words, rule errors in the ticks' words, and the patient's upload, result and plan pages."""

from __future__ import annotations

import datetime

import pytest
from django.urls import reverse
from django.utils import timezone

from analysis.feedback import Grammar
from tests.personas import PASSWORD, make_exercise
from tests.webapp.test_does_not_fit import mismatched  # noqa: F401 (a fixture)
from webapp.audit.models import AuditEvent
from webapp.patients.models import Prescription
from workers import exercise_models


@pytest.fixture
def exercise(world):
    return make_exercise(world.clinic)


def test_a_deactivated_account_is_told_so_with_its_right_password(client, world):
    world.therapist.is_active = False
    world.therapist.save()
    form = {"username": "therapist", "password": PASSWORD}
    page = client.post(reverse("accounts:login"), form).content.decode()
    assert "This account has been deactivated" in page and "didn" not in page
    wrong = client.post(reverse("accounts:login"), {**form, "password": "not-it"})
    assert "deactivated" not in wrong.content.decode()  # nothing said without the password


def test_a_duplicate_rule_is_refused_with_a_message(client, world, exercise):
    client.force_login(world.therapist)
    rule = {"part": "LeftLowerLeg", "direction": "away", "degrees": "25", "moment": "2"}
    rule.update(sentence="Bend your left knee more", said_as="F")
    url = reverse("exercises:add-rule", kwargs={"pk": exercise.pk})
    assert client.post(url, rule).status_code == 302
    again = client.post(url, rule)
    assert again.status_code == 400
    assert "This rule is already in the feedback rules" in again.content.decode()
    exercise.refresh_from_db()
    assert exercise.feedback_grammar.count('-> F:"Bend your left knee more"') == 1


def test_the_audit_log_names_the_exercise_and_says_archive_and_bring_back(client, world, exercise):
    client.force_login(world.therapist)
    url = reverse("exercises:archive", kwargs={"pk": exercise.pk})
    client.post(url)
    client.post(url)
    client.force_login(world.clinic_admin)
    page = client.get(reverse("audit:events")).content.decode()
    assert "<td>Archive</td>" in page and "<td>Bring back</td>" in page
    assert f"exercise “{exercise.name}”" in page
    events = AuditEvent.objects.filter(object_type="Exercise")
    actions = list(events.values_list("action", flat=True))
    assert sorted(actions) == ["archive", "restore"]


def test_rules_name_body_parts_as_the_ticks_do(client, world, exercise, monkeypatch):
    client.force_login(world.therapist)
    url = reverse("exercises:grammar", kwargs={"pk": exercise.pk})

    def verdict(text: str) -> dict:
        return client.post(url, {"text": text}, content_type="application/json").json()

    ticks = 'type$2 & @hips$3 -> F:"Keep your hips level"\n@lower_back$2 -> T:"Stand tall"\n'
    stored = 'type$2 & @waist$2 -> F:"Written before"\n@spine$4 -> F:"Also before"\n'
    assert verdict(ticks)["valid"] and verdict(stored)["valid"]
    refused = verdict('type$2 & @tail$3 -> F:"x"')
    assert not refused["valid"] and (refused["line"], refused["column"]) == (1, 10)
    known = refused["message"].split("it knows ")[1].split(", ")
    assert {"hips", "lower_back", "left_thigh"} <= set(known)
    assert not {"waist", "spine", "Waist", "Spine"} & set(known)
    # The rule picker writes the ticks' words too.
    rule = {"part": "Spine", "direction": "away", "degrees": "25", "moment": "2"}
    rule.update(sentence="Keep your back still", said_as="F")
    assert (
        client.post(reverse("exercises:add-rule", kwargs={"pk": exercise.pk}), rule).status_code
        == 302
    )
    exercise.refresh_from_db()
    assert "@lower_back$" in exercise.feedback_grammar
    # The model is built with the rig's own names, which the analysis matches levels by.
    built = {}
    monkeypatch.setattr(exercise_models, "build_model", lambda tutor, **kw: built.update(kw))
    exercise.feedback_grammar = ticks + stored
    exercise_models.fit_for_exercise(exercise)
    rules = Grammar.parse(built["grammar"])
    assert rules.match(2, {"Waist": 3}).feedbacks == ("Keep your hips level",)
    assert rules.match(1, {"Spine": 2}).tips == ("Stand tall",)
    assert rules.match(2, {"Waist": 2}).feedbacks == ("Written before",)


def test_the_patients_pages_speak_to_a_patient(client, world, exercise):
    today = timezone.localdate()
    other_days = ",".join(d for i, d in enumerate(("mon", "tue", "wed", "thu", "fri", "sat",
                                                   "sun")) if i != today.weekday())  # fmt: skip
    for days in (other_days, ("mon", "tue", "wed", "thu", "fri", "sat", "sun")[today.weekday()]):
        Prescription.objects.create(
            patient=world.patient, exercise=exercise, start_date=today - datetime.timedelta(7),
            days=days, sessions_per_week=len(days.split(",")),
        )  # fmt: skip
    client.force_login(world.patient_user)
    home = client.get(reverse("dashboard:home")).content.decode()
    assert home.count("For today.") == 1 and home.count("Not for today") == 1
    assert f"today, {today:%A}" in home
    upload = client.get(reverse("recordings:upload")).content.decode()
    assert ".bvh" not in upload.lower().replace('accept=".bvh', "") and "Kinect" not in upload
    assert "The file of your session" in upload
    guide = client.get(reverse("help:guide")).content.decode()
    assert "How to record a session" in guide and "Build model" not in guide
    assert "-pw" not in guide and "tutor" not in guide.lower()


def test_a_patients_wrong_exercise_result_asks_nothing_they_cannot_do(
    client,
    world,
    mismatched,  # noqa: F811 (the fixture imported above)
):
    recording = mismatched[0]
    client.force_login(world.patient_user)
    url = reverse("recordings:detail", kwargs={"pk": recording.pk})
    page = client.get(url, follow=True).content.decode()
    assert "does not seem to show the exercise" in page and "record the session again" in page
    assert "moving the recording" not in page and "move the recording" not in page
