"""Goals per patient and exercise (issue 23, item 4): `GET|POST /api/v1/patients/{id}/goals/`
(validation with plain messages, clinic scope, roles, audit), the patient page's "Goals" section
and form, the goal lines on the progress charts, the goals in the progress report, and the home
page's attention entry for a goal off track."""

from __future__ import annotations

import datetime
import json
import re

import pytest
from django.urls import reverse
from django.utils import timezone
from rest_framework.test import APIClient

from analysis.pipeline.results import AngleRange
from tests.personas import make_exercise
from tests.webapp.test_clinical_pages import analysed, pdf_text, section, summary
from webapp.audit.models import AuditEvent
from webapp.dashboard.attention import patients_needing_attention
from webapp.patients.models import Goal
from webapp.reports.content import progress_content
from webapp.reports.pdf import progress_pdf
from webapp.reports.services import progress_report_name

TODAY = timezone.localdate


def url(patient) -> str:
    return f"/api/v1/patients/{patient.pk}/goals/"


def as_user(user) -> APIClient:
    api = APIClient()
    api.force_authenticate(user)
    return api


@pytest.fixture
def squat(world):
    return make_exercise(world.clinic)


def knee_goal(exercise, target: float = 90.0, by: str = "2027-03-12") -> dict:
    return {
        "exercise": str(exercise.pk),
        "measure": "knee_flexion_left",
        "target": target,
        "by": by,
    }


def knee_session(world, exercise, knee_range: float, days_ago: int, score: float = 70.0):
    angles = {"knee_flexion_left": AngleRange(0.0, knee_range)}
    return analysed(world.patient, exercise, summary(score, angles), days_ago=days_ago)


def days_from_today(days: int) -> str:
    return (TODAY() + datetime.timedelta(days=days)).isoformat()


def test_therapist_sets_a_goal_and_reads_it_in_plain_words(world, squat):
    answer = as_user(world.therapist).post(url(world.patient), knee_goal(squat), format="json")
    assert answer.status_code == 201, answer.content
    body = answer.json()
    goal = Goal.objects.get(pk=body["id"])
    assert (goal.patient, goal.exercise, goal.measure) == (
        world.patient,
        squat,
        "knee_flexion_left",
    )
    assert (goal.target, goal.by, goal.created_by) == (
        90.0,
        datetime.date(2027, 3, 12),
        world.therapist,
    )
    assert body["words"] == "Left knee flexion: reach 90° range of motion by 12 March 2027"
    assert body["state"] == "no data" and body["latest"] is None
    listed = as_user(world.patient_user).get(url(world.patient))
    assert listed.status_code == 200
    assert [g["id"] for g in listed.json()["goals"]] == [body["id"]]


def test_a_goal_reads_its_latest_session_and_is_met_when_reached(world, squat):
    knee_session(world, squat, 70.0, days_ago=10)
    knee_session(world, squat, 95.0, days_ago=2)
    as_user(world.therapist).post(url(world.patient), knee_goal(squat), format="json")
    score_goal = {"exercise": str(squat.pk), "measure": "score", "target": 80, "by": "2027-01-01"}
    as_user(world.therapist).post(url(world.patient), score_goal, format="json")
    goals = {
        g["measure"]: g for g in as_user(world.therapist).get(url(world.patient)).json()["goals"]
    }
    knee = goals["knee_flexion_left"]
    assert (knee["first"], knee["latest"], knee["state"]) == (70.0, 95.0, "met")
    assert (goals["score"]["latest"], goals["score"]["state"]) == (70.0, "on track")


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        ({"measure": "knee_bend"}, "measure", "knee_flexion_left"),  # the accepted names listed
        ({"measure": "knee_bend"}, "measure", "adherence"),
        ({"target": "Infinity"}, "target", "finite"),
        ({"target": "NaN"}, "target", "finite"),
        ({"target": 500}, "target", "between"),
        ({"measure": "score", "target": 120}, "target", "between 0 and 100"),
        ({"by": "12/03/2027"}, "by", "YYYY-MM-DD"),
        ({"by": "2027-02-30"}, "by", ""),
        ({"exercise": "not-an-id"}, "exercise", ""),
    ],
)
def test_bad_input_is_400_with_a_plain_message(world, squat, change, field, words):
    answer = as_user(world.therapist).post(
        url(world.patient), {**knee_goal(squat), **change}, format="json"
    )
    assert answer.status_code == 400, answer.content
    message = " ".join(answer.json()[field])
    assert words in message
    assert not Goal.objects.exists()


def test_a_date_in_the_past_is_accepted(world, squat):
    answer = as_user(world.therapist).post(
        url(world.patient), knee_goal(squat, by="2020-01-31"), format="json"
    )
    assert answer.status_code == 201
    assert answer.json()["state"] == "not met"


def test_another_clinics_exercise_is_unknown(world):
    elsewhere = make_exercise(world.other_clinic)
    answer = as_user(world.therapist).post(url(world.patient), knee_goal(elsewhere), format="json")
    assert answer.status_code == 400
    assert answer.json() == {"exercise": ["Unknown exercise."]}


def test_other_clinics_and_other_patients_get_404_and_patients_do_not_set_goals(world, squat):
    for stranger in (world.outsider, world.other_patient_user):
        assert as_user(stranger).get(url(world.patient)).status_code == 404
        answer = as_user(stranger).post(url(world.patient), knee_goal(squat), format="json")
        assert answer.status_code == 404
    answer = as_user(world.therapist).post(
        url(world.outsider_patient), knee_goal(squat), format="json"
    )
    assert answer.status_code == 404
    answer = as_user(world.patient_user).post(url(world.patient), knee_goal(squat), format="json")
    assert answer.status_code == 403
    assert not Goal.objects.exists()


def test_setting_a_goal_is_audited(world, squat):
    answer = as_user(world.clinic_admin).post(url(world.patient), knee_goal(squat), format="json")
    event = AuditEvent.objects.get(action="create", object_type="Goal")
    assert (event.object_id, event.user, event.patient_id) == (
        answer.json()["id"],
        world.clinic_admin,
        world.patient.pk,
    )


def test_patient_page_lists_goals_and_the_form_adds_one(client, world, squat):
    client.force_login(world.therapist)
    form = {
        "exercise": squat.pk,
        "measure": "knee_flexion_left",
        "target": "90",
        "by": "2027-03-12",
    }
    answer = client.post(reverse("patients:add-goal", kwargs={"pk": world.patient.pk}), form)
    assert answer.status_code == 302 and answer["Location"].endswith("#goals")
    detail = reverse("patients:detail", kwargs={"pk": world.patient.pk})
    goals = section(client.get(detail).content.decode(), "goals")
    assert "Left knee flexion: reach 90° range of motion by 12 March 2027" in goals
    assert "Deep squat" in goals and "no sessions yet" in goals
    assert 'id="add-goal"' in goals
    assert "knee_flexion_left" not in re.sub(
        r"<[^>]*>", "", goals
    )  # never the internal name on screen
    client.force_login(world.patient_user)
    answer = client.get(detail)  # the therapist's page: the patient is sent to their own pages
    assert answer.status_code == 302 and answer["Location"] == reverse("dashboard:home")
    progress = client.get(reverse("dashboard:my-progress")).content.decode()
    assert "Left knee flexion" in progress and "90°" in progress
    assert 'id="add-goal"' not in progress


def test_the_page_form_refuses_a_target_out_of_range(client, world, squat):
    client.force_login(world.therapist)
    form = {"exercise": squat.pk, "measure": "score", "target": "150", "by": "2027-03-12"}
    client.post(reverse("patients:add-goal", kwargs={"pk": world.patient.pk}), form)
    assert not Goal.objects.exists()
    client.force_login(world.patient_user)
    form["target"] = "80"
    answer = client.post(reverse("patients:add-goal", kwargs={"pk": world.patient.pk}), form)
    assert answer.status_code == 403 and not Goal.objects.exists()


def test_progress_page_draws_goal_lines_on_the_matching_charts(client, world, squat):
    knee_session(world, squat, 70.0, days_ago=3)
    for goal in (knee_goal(squat), {**knee_goal(squat), "measure": "score", "target": 85}):
        as_user(world.therapist).post(url(world.patient), goal, format="json")
    client.force_login(world.therapist)
    html = client.get(reverse("reports:progress", kwargs={"pk": world.patient.pk})).content.decode()
    lines = json.loads(re.search(r'id="goal-lines"[^>]*>(.*?)</script>', html, re.S)[1])
    by_chart = {line["chart"]: line for line in lines}
    assert (
        by_chart["angle"]["text"] == "goal 90°"
        and by_chart["angle"]["label"] == "Left knee flexion"
    )
    assert by_chart["score"]["text"] == "goal 85 points" and by_chart["score"]["target"] == 85
    assert {line["exercise"] for line in lines} == {"Deep squat"}  # matches the clinical chart's
    assert all(line["by"] == "2027-03-12" for line in lines)


def test_progress_report_lists_each_goal_and_how_it_stands(client, world, squat):
    knee_session(world, squat, 70.0, days_ago=3)
    before = progress_report_name(world.patient, None, None)
    score_goal = {"exercise": str(squat.pk), "measure": "score", "target": 60, "by": "2027-03-12"}
    as_user(world.therapist).post(url(world.patient), score_goal, format="json")
    as_user(world.therapist).post(url(world.patient), knee_goal(squat), format="json")
    assert progress_report_name(world.patient, None, None) != before
    content = progress_content(world.patient, None, None)
    assert [
        "Deep squat",
        "Score: reach a score of 60 / 100 by 12 March 2027",
        "70",
        "met",
    ] in content["goals"]
    text = pdf_text(progress_pdf(content))
    assert "Goals" in text and "reach a score of 60 / 100 by 12 March 2027" in text
    assert "met" in text and "on track" in text
    client.force_login(world.therapist)
    printed = client.get(reverse("reports:progress-print", kwargs={"pk": world.patient.pk}))
    assert "reach a score of 60 / 100 by 12 March 2027" in printed.content.decode()


def goal_reasons(world):
    found = patients_needing_attention(world.clinic.pk)
    return [
        r
        for entry in found
        if entry.patient_id == world.patient.pk
        for r in entry.reasons
        if r.kind == "goal"
    ]


def test_a_goal_past_its_date_and_not_met_needs_attention(world, squat):
    knee_session(world, squat, 70.0, days_ago=5)
    as_user(world.therapist).post(
        url(world.patient), knee_goal(squat, by=days_from_today(-1)), format="json"
    )
    [reason] = goal_reasons(world)
    assert reason.text.startswith(
        "Deep squat: goal not met by its date (Left knee flexion: reach 90°"
    )
    assert "now 70°" in reason.text


def test_a_goal_going_backwards_needs_attention_before_its_date(world, squat):
    knee_session(world, squat, 80.0, days_ago=9)
    knee_session(world, squat, 60.0, days_ago=2)
    as_user(world.therapist).post(
        url(world.patient), knee_goal(squat, by=days_from_today(30)), format="json"
    )
    [reason] = goal_reasons(world)
    assert "goal off track" in reason.text and "now 60°, lower than at the start" in reason.text


@pytest.mark.parametrize(("first", "latest"), [(60.0, 80.0), (60.0, 95.0)])
def test_a_goal_on_track_or_met_needs_no_attention(world, squat, first, latest):
    knee_session(world, squat, first, days_ago=9)
    knee_session(world, squat, latest, days_ago=2)
    by = days_from_today(30 if latest < 90 else -3)  # a met goal stays met after its date
    as_user(world.therapist).post(url(world.patient), knee_goal(squat, by=by), format="json")
    assert goal_reasons(world) == []


def test_an_adherence_goal_past_its_date_is_judged_on_the_last_four_weeks(world, squat):
    world.patient.prescriptions.create(
        exercise=squat, sessions_per_week=3, start_date=TODAY() - datetime.timedelta(days=40)
    )
    knee_session(world, squat, 80.0, days_ago=2)
    goal = {
        "exercise": str(squat.pk),
        "measure": "adherence",
        "target": 80,
        "by": days_from_today(-1),
    }
    body = as_user(world.therapist).post(url(world.patient), goal, format="json").json()
    assert body["state"] == "not met" and body["latest"] < 80
    [reason] = goal_reasons(world)
    assert "Adherence: reach 80 % of the prescribed sessions" in reason.text


def test_the_home_page_shows_the_goal_at_once(client, world, squat):
    as_user(world.therapist).post(
        url(world.patient), knee_goal(squat, by=days_from_today(-2)), format="json"
    )
    client.force_login(world.therapist)
    attention = section(client.get("/").content.decode(), "attention")
    assert "Ann Example" in attention and "goal off track" in attention
    assert "goal not met by its date" in attention
