from django.urls import path

from webapp.exercises import annotate, views

app_name = "exercises"

urlpatterns = [
    path("", views.exercise_list, name="list"),
    path("new/", views.exercise_create, name="create"),
    path("<uuid:pk>/", views.exercise_detail, name="detail"),
    path("<uuid:pk>/edit/", views.exercise_edit, name="edit"),
    path("<uuid:pk>/archive/", views.exercise_archive, name="archive"),
    path("<uuid:pk>/reference/", views.replace_reference, name="reference"),
    path("<uuid:pk>/reference.json", views.reference_data, name="reference-data"),
    path("<uuid:pk>/rules/", annotate.add_rule, name="add-rule"),
    path("<uuid:pk>/build/", views.build_model, name="build"),
    path("<uuid:pk>/models.json", views.model_status, name="model-status"),
    path("<uuid:pk>/annotate/", annotate.annotate_page, name="annotate"),
    path("<uuid:pk>/tutor.json", annotate.tutor_data, name="tutor-data"),
    path("<uuid:pk>/landmarks/", annotate.save_landmarks, name="landmarks"),
    path("<uuid:pk>/grammar/", annotate.check_grammar, name="grammar"),
]
