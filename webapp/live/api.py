"""``POST /api/v1/live-sessions/`` (patient, exercise) → 201 ``{"id": ..., "ws": ...}``."""

from __future__ import annotations

from drf_spectacular.utils import OpenApiResponse, extend_schema, inline_serializer
from rest_framework import serializers, status
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from webapp.accounts.permissions import get_exercise_for_user, get_patient_for_user
from webapp.live import services


class LiveSessionRequest(serializers.Serializer):
    patient = serializers.UUIDField()
    exercise = serializers.UUIDField()


LIVE_SESSION_CREATED = inline_serializer(
    "LiveSessionCreated",
    {"id": serializers.UUIDField(), "ws": serializers.CharField(), "page": serializers.CharField()},
)


class LiveSessionCreate(APIView):
    """Open a live session; stream frames to its WebSocket (see `analysis.live.session`)."""

    @extend_schema(
        request=LiveSessionRequest,
        responses={
            201: LIVE_SESSION_CREATED,
            404: OpenApiResponse(description="No such patient or exercise in your clinic."),
            409: OpenApiResponse(
                description="The exercise has no model built yet: build it first."
            ),
        },
    )
    def post(self, request: Request) -> Response:
        data = LiveSessionRequest(data=request.data)
        data.is_valid(raise_exception=True)
        patient = get_patient_for_user(request, data.validated_data["patient"])
        exercise = get_exercise_for_user(request, data.validated_data["exercise"])
        if exercise.active_model_id is None:  # every frame is aligned with the model
            return Response({"detail": services.NOT_BUILT}, status=status.HTTP_409_CONFLICT)
        live = services.create_session(patient=patient, exercise=exercise, user=request.user)
        body = {"id": str(live.pk), "ws": live.ws_path, "page": f"/live/{live.pk}/"}
        return Response(body, status=status.HTTP_201_CREATED)
