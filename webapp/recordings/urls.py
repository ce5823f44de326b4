from django.urls import path

from webapp.recordings import notes, recognition, recovery_views, video_views, views

app_name = "recordings"

urlpatterns = [
    path("upload/", views.upload, name="upload"),
    path("<uuid:pk>/", views.detail, name="detail"),
    path("<uuid:pk>/status/", views.status, name="status"),
    path("<uuid:pk>/rerun/", views.rerun, name="rerun"),
    path("<uuid:pk>/result.json", views.result, name="result"),
    path("<uuid:pk>/confirm/", recognition.confirm, name="confirm"),
    path("<uuid:pk>/corrections/", views.corrections, name="corrections"),
    path("<uuid:pk>/label/", views.label, name="label"),
    path("<uuid:pk>/move/", recovery_views.move, name="move"),
    path("<uuid:pk>/delete/", recovery_views.delete, name="delete"),
    path("<uuid:pk>/restore/", recovery_views.restore, name="restore"),
    path("deleted/", recovery_views.deleted, name="deleted"),
    path("<uuid:pk>/notes/", notes.add, name="add-note"),
    path("<uuid:pk>/video/", video_views.video, name="video"),
]
