from django.contrib.auth.views import redirect_to_login
from django.urls import path
from drf_spectacular.views import SpectacularAPIView, SpectacularSwaggerView
from rest_framework.permissions import IsAuthenticated

from webapp.accounts import api as accounts_api
from webapp.accounts.tokens import obtain_token
from webapp.api import exports, goals, notes, prescriptions, views
from webapp.live.api import LiveSessionCreate

_swagger = SpectacularSwaggerView.as_view(
    url_name="api-schema", permission_classes=[IsAuthenticated]
)


def api_docs(request):
    """The Swagger page for whoever may read the schema (a sign-in or a token); an anonymous
    browser is sent to the login page rather than shown a page whose schema request fails."""
    if not request.user.is_authenticated and "HTTP_AUTHORIZATION" not in request.META:
        return redirect_to_login(request.get_full_path())
    return _swagger(request)


urlpatterns = [
    path("v1/auth/token/", obtain_token, name="api-token"),
    path("v1/patients/", views.PatientList.as_view(), name="api-patients"),
    path("v1/patients/<uuid:pk>/", views.PatientDetail.as_view(), name="api-patient"),
    path(
        "v1/patients/<uuid:pk>/recordings/",
        views.PatientRecordings.as_view(),
        name="api-patient-recordings",
    ),
    path(
        "v1/patients/<uuid:pk>/progress/",
        views.PatientProgress.as_view(),
        name="api-patient-progress",
    ),
    path(
        "v1/patients/<uuid:pk>/prescriptions/",
        prescriptions.PatientPrescriptions.as_view(),
        name="api-patient-prescriptions",
    ),
    path(
        "v1/patients/<uuid:pk>/history.csv",
        exports.PatientHistoryCSV.as_view(),
        name="api-patient-history-csv",
    ),
    path("v1/patients/<uuid:pk>/fhir/", exports.PatientFHIR.as_view(), name="api-patient-fhir"),
    path("v1/patients/<uuid:pk>/goals/", goals.PatientGoals.as_view(), name="api-patient-goals"),
    path("v1/exercises/", views.ExerciseList.as_view(), name="api-exercises"),
    path("v1/recordings/", views.RecordingCreate.as_view(), name="api-recordings"),
    path("v1/recordings/<uuid:pk>/", views.RecordingDetail.as_view(), name="api-recording"),
    path(
        "v1/recordings/<uuid:pk>/result/",
        views.RecordingResult.as_view(),
        name="api-recording-result",
    ),
    path(
        "v1/recordings/<uuid:pk>/corrections/",
        views.RecordingCorrections.as_view(),
        name="api-recording-corrections",
    ),
    path(
        "v1/recordings/<uuid:pk>/confirm/",
        views.RecordingConfirm.as_view(),
        name="api-recording-confirm",
    ),
    path(
        "v1/recordings/<uuid:pk>/notes/",
        notes.RecordingNotes.as_view(),
        name="api-recording-notes",
    ),
    path("v1/live-sessions/", LiveSessionCreate.as_view(), name="api-live-sessions"),
    path("v1/invitations/", accounts_api.InvitationCreate.as_view(), name="api-invitations"),
    path("v1/users/", accounts_api.UserList.as_view(), name="api-users"),
    path(
        "v1/users/<uuid:pk>/deactivate/",
        accounts_api.UserDeactivate.as_view(),
        name="api-user-deactivate",
    ),
    path(
        "v1/users/<uuid:pk>/reactivate/",
        accounts_api.UserReactivate.as_view(),
        name="api-user-reactivate",
    ),
    path(
        "v1/users/<uuid:pk>/password-link/",
        accounts_api.UserPasswordLink.as_view(),
        name="api-user-password-link",
    ),
    # The schema describes clinical endpoints: only signed-in users and token holders read it.
    path(
        "schema/",
        SpectacularAPIView.as_view(permission_classes=[IsAuthenticated]),
        name="api-schema",
    ),
    # The page that loads the schema asks for the same sign-in, never a page whose request fails.
    path("docs/", api_docs, name="api-docs"),
]
