from django.urls import path

from webapp.reports import api, views

app_name = "reports"

urlpatterns = [
    path("recordings/<uuid:pk>/playback.json", views.playback_json, name="playback"),
    path("recordings/<uuid:pk>/playback.bin", views.playback_bin, name="playback-bin"),
    path("recordings/<uuid:pk>/report.pdf", views.recording_pdf, name="recording-pdf"),
    path("recordings/<uuid:pk>/report/", views.recording_print, name="recording-print"),
    path("patients/<uuid:pk>/progress/", views.progress_page, name="progress"),
    path("patients/<uuid:pk>/report.pdf", views.progress_pdf, name="progress-pdf"),
    path("patients/<uuid:pk>/report/", views.progress_print, name="progress-print"),
    path(
        "api/v1/recordings/<uuid:pk>/report.pdf", api.recording_report, name="api-recording-report"
    ),
    path("api/v1/patients/<uuid:pk>/report.pdf", api.progress_report, name="api-progress-report"),
]
