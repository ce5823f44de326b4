"""Accounts through the API (the interface contract's "Invitations" and "Users").

`POST /api/v1/invitations/` (a clinic admin; a therapist for their own patients) answers 201
`{"id", "url", "expires_at"}`, `url` being the one-time link's path on this site.
`GET /api/v1/users/` (a clinic admin) lists the clinic's accounts; `POST
/api/v1/users/{id}/deactivate/` and `/reactivate/` switch one off and on (a deactivated user's
API tokens and sessions stop working at once); `POST /api/v1/users/{id}/password-link/` answers
a one-time link to choose a new password, shaped like an invitation. Everything is audited.
"""

from __future__ import annotations

from django.core.exceptions import PermissionDenied
from django.http import Http404
from drf_spectacular.types import OpenApiTypes
from drf_spectacular.utils import OpenApiParameter, OpenApiResponse, extend_schema
from rest_framework import generics, serializers, status
from rest_framework.exceptions import ValidationError
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from webapp.accounts import invitations
from webapp.accounts.models import API_ROLES, ROLE_NAMES, Invitation, Role, User
from webapp.accounts.permissions import get_patient_for_user
from webapp.api.numbers import utc_iso
from webapp.audit import log
from webapp.patients.models import Patient

NOT_HERE = OpenApiResponse(description="No such patient or account in your clinic.")
USER_ID = OpenApiParameter(
    "id", OpenApiTypes.UUID, OpenApiParameter.PATH, description="the account's id"
)


class InvitationRequest(serializers.Serializer):
    role = serializers.ChoiceField(choices=sorted(API_ROLES))
    patient = serializers.UUIDField(
        required=False, allow_null=True, help_text="The patient whose login this is (role patient)."
    )
    email = serializers.EmailField(
        required=False, allow_blank=True, help_text="Where to e-mail the link too."
    )


class LinkAnswer(serializers.Serializer):
    id = serializers.UUIDField()
    url = serializers.CharField(help_text="The one-time link's path on this site.")
    expires_at = serializers.DateTimeField()


class AccountSerializer(serializers.Serializer):
    id = serializers.UUIDField()
    username = serializers.CharField()
    role = serializers.ChoiceField(choices=sorted(API_ROLES))
    active = serializers.BooleanField()
    patient = serializers.UUIDField(allow_null=True, help_text="The patient of a patient's login.")


def link_answer(request: Request, invitation: Invitation, key: str) -> Response:
    path = invitations.link_path(invitation, key)
    invitations.send_link(invitation, request.build_absolute_uri(path))
    body = {"id": str(invitation.pk), "url": path, "expires_at": utc_iso(invitation.expires_at)}
    return Response(body, status=status.HTTP_201_CREATED)


def account_json(user: User, patient_id) -> dict:
    return {
        "id": str(user.public_id),
        "username": user.username,
        "role": ROLE_NAMES[user.role],
        "active": user.is_active,
        "patient": str(patient_id) if patient_id else None,
    }


def require_admin(request: Request) -> None:
    if request.user.role != Role.CLINIC_ADMIN or request.user.clinic_id is None:
        raise PermissionDenied("Only the clinic admin can manage accounts.")


def clinic_account(request: Request, pk) -> User:
    """The account `pk` of the caller's clinic (the caller being its admin), else 403 or 404."""
    require_admin(request)
    try:
        return invitations.account_in_clinic(request.user, pk)
    except User.DoesNotExist as error:
        raise Http404("No such account in your clinic.") from error


class InvitationCreate(APIView):
    """Invite someone to the clinic: a therapist, an admin, or a patient (their login)."""

    @extend_schema(request=InvitationRequest, responses={201: LinkAnswer, 404: NOT_HERE})
    def post(self, request: Request) -> Response:
        if not request.user.is_staff_member:
            raise PermissionDenied("Patients cannot invite anyone.")
        form = InvitationRequest(data=request.data)
        form.is_valid(raise_exception=True)
        data = form.validated_data
        role = API_ROLES[data["role"]]
        if role != Role.PATIENT and request.user.role != Role.CLINIC_ADMIN:
            raise PermissionDenied("Only the clinic admin invites therapists and admins.")
        patient = None
        if data.get("patient"):
            patient = get_patient_for_user(request, data["patient"], audit=False)
        try:
            invitation, key = invitations.create_invitation(
                request.user, role, patient, data.get("email", "")
            )
        except ValueError as error:
            raise ValidationError({"patient": [str(error)]}) from error
        log.record(request, "create", invitation, patient_id=invitation.patient_id)
        return link_answer(request, invitation, key)


class UserList(generics.ListAPIView):
    """The clinic's accounts (its admin only)."""

    serializer_class = AccountSerializer

    def get_queryset(self):
        require_admin(self.request)
        return User.objects.filter(clinic_id=self.request.user.clinic_id).order_by("username")

    def list(self, request: Request, *args, **kwargs) -> Response:
        page = self.paginate_queryset(self.get_queryset())
        patients = dict(
            Patient.objects.filter(user__in=[u.pk for u in page]).values_list("user_id", "pk")
        )
        return self.get_paginated_response([account_json(u, patients.get(u.pk)) for u in page])


def patient_of(account: User):
    return Patient.objects.filter(user=account).values_list("pk", flat=True).first()


class UserActivation(APIView):
    active = True

    @extend_schema(
        parameters=[USER_ID], request=None, responses={200: AccountSerializer, 404: NOT_HERE}
    )
    def post(self, request: Request, pk) -> Response:
        account = clinic_account(request, pk)
        try:
            invitations.set_active(request.user, account, self.active)
        except ValueError as error:
            raise ValidationError({"detail": str(error)}) from error
        patient_id = patient_of(account)
        log.record(request, "update", account, patient_id=patient_id)
        return Response(account_json(account, patient_id))


class UserDeactivate(UserActivation):
    """Switch an account off: its API tokens are revoked and its sessions end at once."""

    active = False


class UserReactivate(UserActivation):
    """Switch an account on again (its earlier API tokens stay revoked)."""

    active = True


class UserPasswordLink(APIView):
    """A one-time link for the account to choose a new password (e-mailed if it has an address)."""

    @extend_schema(parameters=[USER_ID], request=None, responses={201: LinkAnswer, 404: NOT_HERE})
    def post(self, request: Request, pk) -> Response:
        account = clinic_account(request, pk)
        invitation, key = invitations.create_password_link(request.user, account)
        log.record(request, "update", account, patient_id=patient_of(account))
        return link_answer(request, invitation, key)
