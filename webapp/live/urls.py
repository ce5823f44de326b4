from django.urls import path

from webapp.live import views

app_name = "live"

urlpatterns = [
    path("<uuid:pk>/", views.page, name="page"),
    path("<uuid:pk>/status/", views.status, name="status"),
    path("<uuid:pk>/watch/", views.watch, name="watch"),
    path("start/<uuid:pk>/", views.start, name="start"),
    path("replay/<uuid:pk>/", views.replay, name="replay"),
]
