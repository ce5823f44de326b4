from django.urls import path

from webapp.live import views

app_name = "live"

urlpatterns = [
    path("<uuid:pk>/", views.page, name="page"),
    path("<uuid:pk>/status/", views.status, name="status"),
    path("replay/<uuid:pk>/", views.replay, name="replay"),
]
