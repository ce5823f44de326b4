"""The camera page: ``/my/live/camera/<prescription id>/`` (the interface contract, the camera)."""

from django.urls import path

from webapp.live import camera_views

app_name = "camera"

urlpatterns = [
    path("<uuid:pk>/", camera_views.page, name="page"),
    path("<uuid:pk>/start/", camera_views.start, name="start"),
]
