from django.urls import path

from webapp.exercises import views

app_name = "exercises"

urlpatterns = [
    path("", views.exercise_list, name="list"),
    path("new/", views.exercise_create, name="create"),
    path("<uuid:pk>/", views.exercise_detail, name="detail"),
    path("<uuid:pk>/build/", views.build_model, name="build"),
    path("<uuid:pk>/models.json", views.model_status, name="model-status"),
]
