from django.urls import path

from webapp.patients import compare, goal_views, history, views

app_name = "patients"

urlpatterns = [
    path("", views.patient_list, name="list"),
    path("new/", views.patient_create, name="create"),
    path("<uuid:pk>/", views.patient_detail, name="detail"),
    path("<uuid:pk>/edit/", views.patient_edit, name="edit"),
    path("<uuid:pk>/archive/", views.patient_archive, name="archive"),
    path("<uuid:pk>/prescriptions/new/", views.prescription_create, name="prescribe"),
    path("<uuid:pk>/progress.json", history.progress_json, name="progress"),
    path("<uuid:pk>/history.csv", history.history_csv, name="history-csv"),
    path("<uuid:pk>/goals/", goal_views.add, name="add-goal"),
    path("<uuid:pk>/compare/", compare.compare, name="compare"),
]
