from django.urls import path

from webapp.dashboard import patient_progress, patient_result, views

app_name = "dashboard"

urlpatterns = [
    path("", views.home, name="home"),
    # The patient's own pages (issue 24).
    path("my/progress/", patient_progress.progress, name="my-progress"),
    path(
        "my/exercises/<uuid:pk>/reference.json",
        patient_progress.reference,
        name="my-reference",
    ),
    path("my/recordings/<uuid:pk>/effort/", patient_result.effort, name="my-effort"),
]
