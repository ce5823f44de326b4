"""`GET|POST /api/v1/patients/{id}/goals/`: a patient's goals with how each stands.

`measure` is a clinical angle name (as in `clinical_angles`, e.g. "knee_flexion_left": its range
of motion in degrees), "score" or "adherence" (%); `webapp.patients.goals` says when a goal is
met, on track or off track. The clinic's staff set goals; a patient reads their own.
"""

from __future__ import annotations

from typing import Any

from drf_spectacular.utils import extend_schema
from rest_framework import serializers, status
from rest_framework.exceptions import PermissionDenied
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from webapp.accounts.permissions import get_patient_for_user, visible_exercises
from webapp.api.serializers import UTCDateTimeField
from webapp.patients.goal_views import save_goal
from webapp.patients.goals import (
    FINITE,
    MEASURES,
    STATE_WORDS,
    GoalStatus,
    measure_error,
    patient_goal_statuses,
    statuses,
    target_error,
)


class GoalSerializer(serializers.Serializer):
    id = serializers.UUIDField()
    exercise = serializers.UUIDField()
    exercise_name = serializers.CharField()
    measure = serializers.CharField()
    target = serializers.FloatField()
    by = serializers.DateField()
    words = serializers.CharField(help_text="the goal in plain words")
    first = serializers.FloatField(allow_null=True, help_text="the first session's value")
    latest = serializers.FloatField(allow_null=True, help_text="the latest value")
    state = serializers.ChoiceField(choices=list(STATE_WORDS))
    created_at = UTCDateTimeField()


class GoalsSerializer(serializers.Serializer):
    patient = serializers.UUIDField()
    goals = GoalSerializer(many=True)


class GoalInputSerializer(serializers.Serializer):
    exercise = serializers.UUIDField()
    measure = serializers.CharField(max_length=60, help_text=f"one of: {', '.join(MEASURES)}")
    target = serializers.FloatField(error_messages={"invalid": FINITE})
    by = serializers.DateField(help_text="YYYY-MM-DD")

    def validate_measure(self, measure: str) -> str:
        problem = measure_error(measure)
        if problem:
            raise serializers.ValidationError(problem)
        return measure

    def validate(self, data: dict[str, Any]) -> dict[str, Any]:
        problem = target_error(data["measure"], data["target"])
        if problem:
            raise serializers.ValidationError({"target": problem})
        return data


def goal_row(found: GoalStatus) -> dict[str, Any]:
    goal = found.goal
    row = {
        "id": goal.pk,
        "exercise": goal.exercise_id,
        "exercise_name": goal.exercise.name,
        "measure": goal.measure,
        "target": goal.target,
        "by": goal.by,
        "words": found.words,
        "first": found.first,
        "latest": found.latest,
        "state": found.state,
        "created_at": goal.created_at,
    }
    return GoalSerializer(row).data


class PatientGoals(APIView):
    """A patient's goals, by date; the clinic's staff add new ones."""

    @extend_schema(responses={200: GoalsSerializer})
    def get(self, request: Request, pk) -> Response:
        patient = get_patient_for_user(request, pk)
        goals = [goal_row(found) for found in patient_goal_statuses(patient)]
        return Response({"patient": str(patient.pk), "goals": goals})

    @extend_schema(request=GoalInputSerializer, responses={201: GoalSerializer})
    def post(self, request: Request, pk) -> Response:
        patient = get_patient_for_user(request, pk, audit=False)  # the goal is the event
        if not request.user.is_staff_member:
            raise PermissionDenied("Only the clinic's therapists set goals.")
        data = GoalInputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        fields = dict(data.validated_data)
        exercise = visible_exercises(request.user).filter(pk=fields.pop("exercise")).first()
        if exercise is None:
            raise serializers.ValidationError({"exercise": ["Unknown exercise."]})
        goal = save_goal(request, patient, {**fields, "exercise": exercise})
        return Response(goal_row(statuses([goal])[0]), status=status.HTTP_201_CREATED)
