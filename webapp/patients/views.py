from __future__ import annotations

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.core.paginator import Page, Paginator
from django.db.models import Prefetch, Q
from django.http import HttpRequest, HttpResponse
from django.shortcuts import redirect, render
from django.utils import timezone
from django.views.decorators.http import require_POST

from webapp.accounts.invitations import may_invite
from webapp.accounts.models import Role
from webapp.accounts.permissions import get_patient_for_user, require_staff, visible_patients
from webapp.patients.adherence import DaysWithData, patient_adherence
from webapp.patients.forms import PatientForm, PrescriptionForm
from webapp.patients.goal_views import goal_form
from webapp.patients.goals import patient_goal_statuses
from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun
from webapp.recordings.reading import attach_readings

PAGE_SIZE = 25
RECORDINGS_PER_PAGE = 20


@login_required
@require_staff
def patient_list(request: HttpRequest) -> HttpResponse:
    query = request.GET.get("q", "").strip()
    show_archived = request.GET.get("archived") == "1"
    patients = visible_patients(request.user).filter(archived_at__isnull=not show_archived)
    if query:
        patients = patients.filter(Q(display_name__icontains=query) | Q(notes__icontains=query))
    patients = patients.order_by("display_name")
    page = Paginator(patients, PAGE_SIZE).get_page(request.GET.get("page"))
    context = {"page": page, "query": query, "show_archived": show_archived}
    return render(request, "patients/list.html", context)


def with_adherence(patient: Patient) -> tuple[list, DaysWithData]:
    """The patient's prescriptions, each with its `adherence`, and their days with data."""
    prescriptions = list(patient.prescriptions.select_related("exercise"))
    found, days = patient_adherence(patient, prescriptions=prescriptions)
    for prescription, figures in zip(prescriptions, found, strict=True):
        prescription.adherence = figures
    return prescriptions, days


@login_required
def patient_detail(request: HttpRequest, pk) -> HttpResponse:
    patient = get_patient_for_user(request, pk)
    if request.user.is_patient:  # the patient's own pages say the same in their words
        return redirect("dashboard:home")
    prescriptions, days = with_adherence(patient)
    context = {
        "patient": patient,
        "prescriptions": prescriptions,
        "days_with_data": days,
        "recordings": recordings_page(patient, request.GET.get("recordings_page")),
        "levels": patient.levels.select_related("exercise").order_by("exercise__name", "joint"),
        "can_invite": patient.user_id is None and may_invite(request.user, Role.PATIENT, patient),
        "goals": patient_goal_statuses(patient),
    }
    if request.user.is_staff_member:
        context["goal_form"] = goal_form(request)
    return render(request, "patients/detail.html", context)


def recordings_page(patient: Patient, number) -> Page:
    """One page of the patient's recordings, newest first, each with its newest run's status and
    the score of its newest succeeded run (`latest`, `score`): every recording can be opened."""
    # Status and score columns only: never load the summaries (10–20 kB each).
    runs = AnalysisRun.objects.only("recording", "status", "score", "progress", "created_at")
    recordings = patient.recordings.select_related("exercise").prefetch_related(
        Prefetch("runs", queryset=runs.order_by("-created_at"))
    )
    page = Paginator(recordings, RECORDINGS_PER_PAGE).get_page(number)
    for recording in page.object_list:
        ordered = list(recording.runs.all())
        recording.latest = ordered[0] if ordered else None
        succeeded = recording.latest_succeeded_run()
        recording.score = succeeded.score if succeeded else None
    attach_readings(page.object_list)  # fits and pass count: the run's one reading
    return page


@login_required
@require_staff
def patient_create(request: HttpRequest) -> HttpResponse:
    form = PatientForm(request.POST or None)
    if request.method == "POST" and form.is_valid():
        patient: Patient = form.save(commit=False)
        patient.clinic = request.user.clinic
        patient.save()
        patient.therapists.add(request.user)
        messages.success(request, f"Patient {patient.display_name} created.")
        return redirect("patients:detail", pk=patient.pk)
    return render(request, "patients/form.html", {"form": form, "title": "New patient"})


@login_required
@require_staff
def patient_edit(request: HttpRequest, pk) -> HttpResponse:
    patient = get_patient_for_user(request, pk)
    form = PatientForm(request.POST or None, instance=patient)
    if request.method == "POST" and form.is_valid():
        form.save()
        messages.success(request, "Changes saved.")
        return redirect("patients:detail", pk=patient.pk)
    context = {"form": form, "title": f"Edit {patient.display_name}", "patient": patient}
    return render(request, "patients/form.html", context)


@login_required
@require_staff
@require_POST
def patient_archive(request: HttpRequest, pk) -> HttpResponse:
    patient = get_patient_for_user(request, pk)
    patient.archived_at = None if patient.archived_at else timezone.now()
    patient.save(update_fields=["archived_at"])
    state = "archived" if patient.archived_at else "restored"
    messages.success(request, f"Patient {patient.display_name} {state}.")
    return redirect("patients:detail", pk=patient.pk)


@login_required
@require_staff
def prescription_create(request: HttpRequest, pk) -> HttpResponse:
    patient = get_patient_for_user(request, pk)
    form = PrescriptionForm(request.POST or None, clinic=request.user.clinic)
    if request.method == "POST" and form.is_valid():
        prescription = form.save(commit=False)
        prescription.patient = patient
        prescription.save()
        messages.success(request, "Prescription added.")
        return redirect("patients:detail", pk=patient.pk)
    context = {"form": form, "title": f"Prescribe for {patient.display_name}", "patient": patient}
    return render(request, "patients/form.html", context)
