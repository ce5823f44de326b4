"""The clinic admin's view of the audit log: every event of their clinic, filterable, paginated."""

from __future__ import annotations

from django import forms
from django.contrib.auth.decorators import login_required
from django.core.paginator import Paginator
from django.http import HttpRequest, HttpResponse
from django.shortcuts import render

from webapp.accounts.models import User
from webapp.accounts.permissions import require_clinic_admin
from webapp.audit.models import AuditEvent
from webapp.patients.models import Patient

PAGE_SIZE = 50


class EventFilter(forms.Form):
    patient = forms.ModelChoiceField(queryset=Patient.objects.none(), required=False)
    user = forms.ModelChoiceField(queryset=User.objects.none(), required=False)
    action = forms.ChoiceField(
        choices=[("", "any action"), *AuditEvent.Action.choices], required=False
    )

    def __init__(self, *args, clinic_id: int, **kwargs):
        super().__init__(*args, **kwargs)
        self.fields["patient"].queryset = Patient.objects.filter(clinic_id=clinic_id).order_by(
            "display_name"
        )
        self.fields["user"].queryset = User.objects.filter(clinic_id=clinic_id).order_by("username")


def filtered_events(form: EventFilter, clinic_id: int):
    events = AuditEvent.objects.filter(clinic_id=clinic_id)
    if not form.is_valid():
        return events
    data = form.cleaned_data
    if data["patient"] is not None:
        events = events.filter(patient_id=data["patient"].pk)
    if data["user"] is not None:
        events = events.filter(user=data["user"])
    if data["action"]:
        events = events.filter(action=data["action"])
    return events


@login_required
@require_clinic_admin
def event_list(request: HttpRequest) -> HttpResponse:
    clinic_id = request.user.clinic_id
    form = EventFilter(request.GET or None, clinic_id=clinic_id)
    events = filtered_events(form, clinic_id).order_by("-at", "-id")
    page = Paginator(events, PAGE_SIZE).get_page(request.GET.get("page"))
    names = dict(
        Patient.objects.filter(pk__in={e.patient_id for e in page if e.patient_id}).values_list(
            "pk", "display_name"
        )
    )
    query = request.GET.copy()
    query.pop("page", None)
    rows = [(event, names.get(event.patient_id, "")) for event in page]
    context = {"form": form, "page": page, "rows": rows, "filters": query.urlencode()}
    return render(request, "audit/events.html", context)
