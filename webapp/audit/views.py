"""The clinic admin's view of the audit log: every event of their clinic, filterable by patient,
user, action and dates (UTC days, both ends included), paginated, and the filtered rows as CSV."""

from __future__ import annotations

import csv
import datetime
from collections.abc import Iterable, Iterator
from typing import Any

from django import forms
from django.contrib.auth.decorators import login_required
from django.core.paginator import Paginator
from django.db.models import QuerySet
from django.http import HttpRequest, HttpResponse, StreamingHttpResponse
from django.shortcuts import render
from django.utils.text import slugify

from webapp.accounts.models import User
from webapp.accounts.permissions import require_clinic_admin
from webapp.audit.models import AuditEvent
from webapp.patients.history_export import spreadsheet_text
from webapp.patients.models import Patient

PAGE_SIZE = 50
CSV_COLUMNS = ["when (UTC)", "who", "action", "what", "patient", "path", "from", "via"]


class DateInput(forms.DateInput):
    input_type = "date"


class EventFilter(forms.Form):
    patient = forms.ModelChoiceField(queryset=Patient.objects.none(), required=False)
    user = forms.ModelChoiceField(queryset=User.objects.none(), required=False)
    action = forms.ChoiceField(
        choices=[("", "any action"), *AuditEvent.Action.choices], required=False
    )
    since = forms.DateField(label="From", required=False, widget=DateInput)
    until = forms.DateField(label="To", required=False, widget=DateInput)

    def __init__(self, *args, clinic_id: int, **kwargs):
        super().__init__(*args, **kwargs)
        self.fields["patient"].queryset = Patient.objects.filter(clinic_id=clinic_id).order_by(
            "display_name"
        )
        self.fields["user"].queryset = User.objects.filter(clinic_id=clinic_id).order_by("username")

    def clean(self):
        data = super().clean()
        since, until = data.get("since"), data.get("until")
        if since and until and since > until:
            raise forms.ValidationError("The first day comes after the last one.")
        return data


def utc_midnight(day: datetime.date) -> datetime.datetime:
    return datetime.datetime.combine(day, datetime.time.min, tzinfo=datetime.UTC)


def within_days(events: QuerySet[AuditEvent], since, until) -> QuerySet[AuditEvent]:
    """Events on the UTC days `since`..`until` (the page shows times in UTC)."""
    if since:
        events = events.filter(at__gte=utc_midnight(since))
    if until:
        events = events.filter(at__lt=utc_midnight(until + datetime.timedelta(days=1)))
    return events


def filtered_events(form: EventFilter, clinic_id: int) -> QuerySet[AuditEvent]:
    """The clinic's events the filter asks for, newest first; none for a filter that is not valid
    (a mistyped date never widens the rows shown or exported)."""
    events = AuditEvent.objects.filter(clinic_id=clinic_id)
    if form.is_bound and not form.is_valid():
        return events.none()
    data = form.cleaned_data if form.is_bound else {}
    if data.get("patient") is not None:
        events = events.filter(patient_id=data["patient"].pk)
    if data.get("user") is not None:
        events = events.filter(user=data["user"])
    if data.get("action"):
        events = events.filter(action=data["action"])
    events = within_days(events, data.get("since"), data.get("until"))
    return events.order_by("-at", "-id")


def patient_names(clinic_id: int, events: Iterable[AuditEvent] | None = None) -> dict[Any, str]:
    """Patient id → name, deleted patients included (their events stay in the log)."""
    patients = Patient.all_objects.filter(clinic_id=clinic_id)
    if events is not None:
        patients = patients.filter(pk__in={e.patient_id for e in events if e.patient_id})
    return dict(patients.values_list("pk", "display_name"))


def event_filter(request: HttpRequest) -> EventFilter:
    return EventFilter(request.GET or None, clinic_id=request.user.clinic_id)


@login_required
@require_clinic_admin
def event_list(request: HttpRequest) -> HttpResponse:
    clinic_id = request.user.clinic_id
    form = event_filter(request)
    events = filtered_events(form, clinic_id)
    page = Paginator(events, PAGE_SIZE).get_page(request.GET.get("page"))
    names = patient_names(clinic_id, page)
    query = request.GET.copy()
    query.pop("page", None)
    rows = [(event, names.get(event.patient_id, "")) for event in page]
    context = {"form": form, "page": page, "rows": rows, "filters": query.urlencode()}
    return render(request, "audit/events.html", context)


class Echo:
    """A file-like object whose `write` hands the line back, to stream a CSV row by row."""

    def write(self, value: str) -> str:
        return value


def csv_row(event: AuditEvent, patient: str) -> list[str]:
    return [
        event.at.astimezone(datetime.UTC).strftime("%Y-%m-%d %H:%M:%S"),
        spreadsheet_text(event.username),
        event.get_action_display(),
        spreadsheet_text(event.what),
        spreadsheet_text(patient),
        spreadsheet_text(event.path),
        event.ip_address or "",
        event.via,
    ]


def csv_lines(events: QuerySet[AuditEvent], names: dict[Any, str]) -> Iterator[str]:
    writer = csv.writer(Echo())
    yield writer.writerow(CSV_COLUMNS)
    for event in events.iterator(chunk_size=2000):  # a clinic's log can run to millions of rows
        yield writer.writerow(csv_row(event, names.get(event.patient_id, "")))


def export_filename(request: HttpRequest, form: EventFilter) -> str:
    data = form.cleaned_data if form.is_bound and form.is_valid() else {}
    days = [str(day) for day in (data.get("since"), data.get("until")) if day]
    return "-".join(["audit", slugify(request.user.clinic.name) or "clinic", *days]) + ".csv"


@login_required
@require_clinic_admin
def event_csv(request: HttpRequest) -> HttpResponse:
    """The rows the same filter shows on the page, every page of them, newest first."""
    clinic_id = request.user.clinic_id
    form = event_filter(request)
    if form.is_bound and not form.is_valid():
        errors = "; ".join(str(e) for errs in form.errors.values() for e in errs)
        return HttpResponse(errors, status=400, content_type="text/plain; charset=utf-8")
    events = filtered_events(form, clinic_id)
    lines = csv_lines(events, patient_names(clinic_id))
    response = StreamingHttpResponse(lines, content_type="text/csv; charset=utf-8")
    response["Content-Disposition"] = f'attachment; filename="{export_filename(request, form)}"'
    return response
