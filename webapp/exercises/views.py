from __future__ import annotations

import hashlib
import uuid

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.core.files.base import ContentFile
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import redirect, render
from django.views.decorators.http import require_POST

from webapp.accounts.permissions import get_exercise_for_user, require_staff, visible_exercises
from webapp.exercises import services
from webapp.exercises.forms import ExerciseForm
from webapp.exercises.models import Exercise, ExerciseModel, ModelStatus
from webapp.exercises.training_report import training_report


@login_required
@require_staff
def exercise_list(request: HttpRequest) -> HttpResponse:
    exercises = visible_exercises(request.user).filter(archived_at__isnull=True)
    exercises = exercises.select_related("active_model")
    return render(request, "exercises/list.html", {"exercises": exercises})


@login_required
@require_staff
def exercise_create(request: HttpRequest) -> HttpResponse:
    form = ExerciseForm(request.POST or None, request.FILES or None, clinic=request.user.clinic)
    if request.method == "POST" and form.is_valid():
        exercise = save_new_exercise(form, request.user.clinic)
        messages.success(request, f"Exercise {exercise.name} created. Mark its key poses next.")
        return redirect("exercises:detail", pk=exercise.pk)
    status = 400 if request.method == "POST" else 200
    return render(request, "exercises/form.html", {"form": form}, status=status)


def save_new_exercise(form: ExerciseForm, clinic) -> Exercise:
    exercise: Exercise = form.save(commit=False)
    exercise.clinic = clinic
    exercise.tutor_landmark_frames = form.cleaned_data["frames_list"]
    exercise.tutor_landmark_types = form.cleaned_data["types_list"]
    types = sorted(set(exercise.tutor_landmark_types))
    exercise.landmark_type_names = {str(t): f"key pose {t}" for t in types}
    content = form.parsed.content
    exercise.tutor_checksum = hashlib.sha256(content).hexdigest()
    suffix = ".bvh.gz" if content[:2] == b"\x1f\x8b" else ".bvh"
    exercise.tutor_file.save(f"{exercise.pk}{suffix}", ContentFile(content), save=False)
    exercise.save()
    return exercise


@login_required
@require_staff
def exercise_detail(request: HttpRequest, pk) -> HttpResponse:
    exercise = get_exercise_for_user(request, pk)
    context = {"exercise": exercise, "versions": exercise.models.all()[:20]}
    row = shown_model(exercise, request.GET.get("model"))
    if row is not None:
        context.update(model=row, report=training_report(row))
    return render(request, "exercises/detail.html", context)


def shown_model(exercise: Exercise, wanted: str | None) -> ExerciseModel | None:
    """The ready model whose training report the page shows: ?model=ID, else the active one."""
    ready = exercise.models.filter(status=ModelStatus.READY).select_related("exercise")
    try:
        uuid.UUID(str(wanted))
    except ValueError:
        return ready.filter(pk=exercise.active_model_id).first()
    return ready.filter(pk=wanted).first()


@login_required
@require_staff
@require_POST
def build_model(request: HttpRequest, pk) -> HttpResponse:
    exercise = get_exercise_for_user(request, pk)
    if not exercise.tutor_landmark_frames:
        messages.error(request, "Mark the tutor's key poses before building the model.")
    else:
        row = services.start_model_build(exercise)
        messages.success(request, f"Building model version {row.version}.")
    return redirect("exercises:detail", pk=exercise.pk)


@login_required
@require_staff
def model_status(request: HttpRequest, pk) -> JsonResponse:
    exercise = get_exercise_for_user(request, pk)
    rows = exercise.models.all()[:10]
    return JsonResponse(
        {
            "active": str(exercise.active_model_id) if exercise.active_model_id else None,
            "versions": [
                {"id": str(r.pk), "version": r.version, "status": r.status, "progress": r.progress}
                for r in rows
            ],
        }
    )
