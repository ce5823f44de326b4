"""The patient page's goal form: therapists and clinic admins set a goal for one exercise.

Adding a goal refreshes the patient's row of the home page's attention list at once, as a goal
set with a date already past (or a series already going backwards) needs attention now.
"""

from __future__ import annotations

import datetime

from django import forms
from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse
from django.shortcuts import redirect
from django.urls import reverse
from django.utils import timezone
from django.views.decorators.http import require_POST

from webapp.accounts.permissions import get_patient_for_user, require_staff, visible_exercises
from webapp.audit import log
from webapp.dashboard.precompute import refresh_patient
from webapp.patients.forms import ISO_DATE
from webapp.patients.goals import FINITE, MEASURES, measure_label, target_error, unit_of
from webapp.patients.models import Goal, Patient

MEASURE_CHOICES = [(m, f"{measure_label(m)} ({unit_of(m)})") for m in MEASURES]


class GoalForm(forms.Form):
    exercise = forms.ModelChoiceField(queryset=None, empty_label=None)
    measure = forms.ChoiceField(choices=MEASURE_CHOICES, label="What to reach")
    target = forms.FloatField(label="Target", error_messages={"invalid": FINITE})
    by = forms.DateField(
        label="By", widget=forms.DateInput(attrs={"type": "date"}, format=ISO_DATE)
    )

    def __init__(self, *args, exercises, **kwargs):
        super().__init__(*args, **kwargs)
        self.fields["exercise"].queryset = exercises

    def clean(self):
        data = super().clean()
        if "measure" in data and "target" in data:
            problem = target_error(data["measure"], data["target"])
            if problem:
                self.add_error("target", problem)
        return data


def default_date() -> datetime.date:
    """Six weeks from today: a usual span between reviews."""
    return timezone.localdate() + datetime.timedelta(weeks=6)


def goal_form(request: HttpRequest, data=None) -> GoalForm:
    exercises = visible_exercises(request.user).filter(archived_at__isnull=True).order_by("name")
    return GoalForm(data, exercises=exercises, initial={"measure": "score", "by": default_date()})


def save_goal(request: HttpRequest, patient: Patient, data: dict) -> Goal:
    """Store a goal (audited) and bring the patient's attention entry up to date."""
    goal = Goal.objects.create(patient=patient, created_by=request.user, **data)
    log.record(request, "create", goal, patient_id=patient.pk)
    refresh_patient(patient.pk, patient.clinic_id)
    return goal


@login_required
@require_staff
@require_POST
def add(request: HttpRequest, pk) -> HttpResponse:
    patient = get_patient_for_user(request, pk, audit=False)  # the goal is the event
    form = goal_form(request, request.POST)
    if form.is_valid():
        save_goal(request, patient, form.cleaned_data)
        messages.success(request, "Goal added.")
    else:  # nothing written: the visit is a read of the patient's record
        log.record(request, "read", patient, patient_id=patient.pk)
        problems = "; ".join(e for errors in form.errors.values() for e in errors)
        messages.error(request, f"The goal was not saved: {problems}")
    return redirect(reverse("patients:detail", kwargs={"pk": patient.pk}) + "#goals")
