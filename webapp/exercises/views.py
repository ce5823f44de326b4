from __future__ import annotations

import uuid

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import redirect, render
from django.utils import timezone
from django.views.decorators.http import require_POST

from webapp.accounts.permissions import get_exercise_for_user, require_staff, visible_exercises
from webapp.audit import log
from webapp.exercises import services
from webapp.exercises.annotate_data import tutor_pose
from webapp.exercises.forms import ExerciseEditForm, ExerciseForm, ReferenceForm
from webapp.exercises.models import Exercise, ExerciseModel, ModelStatus
from webapp.exercises.training_report import training_report
from webapp.recordings.sources import kind_reliability

READING_VIDEO = (
    "The reference video is still being read: the person is found in each of its frames, "
    "about a minute for a minute of video."
)


@login_required
@require_staff
def exercise_list(request: HttpRequest) -> HttpResponse:
    show_archived = request.GET.get("archived") == "1"
    exercises = visible_exercises(request.user).filter(archived_at__isnull=not show_archived)
    exercises = exercises.select_related("active_model")
    context = {"exercises": exercises, "show_archived": show_archived}
    return render(request, "exercises/list.html", context)


@login_required
@require_staff
def exercise_create(request: HttpRequest) -> HttpResponse:
    form = ExerciseForm(request.POST or None, request.FILES or None, clinic=request.user.clinic)
    if request.method == "POST" and form.is_valid():
        exercise = save_new_exercise(form, request.user.clinic)
        log.record(request, "create", exercise)
        messages.success(request, created_message(exercise))
        return redirect("exercises:detail", pk=exercise.pk)
    status = 400 if request.method == "POST" else 200
    context = {
        "form": form,
        "title": "New exercise",
        "intro": "Give the exercise a name and upload a recording of it done well (the "
        "reference). Next you mark its key poses, such as the start and the end of the movement, "
        "on a chart of the reference.",
        "submit": "Create exercise",
    }
    return render(request, "exercises/form.html", context, status=status)


def created_message(exercise: Exercise) -> str:
    if exercise.tutor_is_video:
        return (
            f"Exercise {exercise.name} created. Its video is being read (about a minute for a "
            "minute of video); key poses are then suggested for you to check."
        )
    return f"Exercise {exercise.name} created. Mark its key poses next."


def save_new_exercise(form: ExerciseForm, clinic) -> Exercise:
    exercise: Exercise = form.save(commit=False)
    exercise.clinic = clinic
    exercise.tutor_landmark_frames = form.cleaned_data["frames_list"]
    exercise.tutor_landmark_types = form.cleaned_data["types_list"]
    types = sorted(set(exercise.tutor_landmark_types))
    exercise.landmark_type_names = {str(t): f"key pose {t}" for t in types}
    services.create_exercise(exercise, form.parsed)
    return exercise


@login_required
@require_staff
def exercise_detail(request: HttpRequest, pk) -> HttpResponse:
    exercise = get_exercise_for_user(request, pk)
    context = {
        "exercise": exercise,
        "versions": exercise.models.all()[:20],
        # A reference video is read by the worker; until then the page has no motion to show.
        "tutor_ready": exercise.tutor_ready(),
        "measured_with": kind_reliability(exercise.tutor_kind()),
    }
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
        messages.error(request, "Mark the reference's key poses before building the model.")
    elif exercise.key_poses_to_confirm:
        messages.error(request, "Check and save the new reference's key poses first.")
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


@login_required
@require_staff
def exercise_edit(request: HttpRequest, pk) -> HttpResponse:
    exercise = get_exercise_for_user(request, pk)
    title = f"Change {exercise.name}"  # before the form writes a posted name into the row
    form = ExerciseEditForm(request.POST or None, instance=exercise)
    if request.method == "POST" and form.is_valid():
        form.save()
        log.record(request, "update", exercise)
        messages.success(request, f"Exercise {exercise.name} saved.")
        return redirect("exercises:detail", pk=exercise.pk)
    status = 400 if request.method == "POST" else 200
    context = {"form": form, "title": title, "exercise": exercise}
    return render(request, "exercises/form.html", context, status=status)


@login_required
@require_staff
def exercise_archive(request: HttpRequest, pk) -> HttpResponse:
    """GET asks to confirm; POST archives an active exercise or brings back an archived one."""
    exercise = get_exercise_for_user(request, pk)
    if request.method != "POST":
        return render(request, "exercises/archive.html", {"exercise": exercise})
    exercise.archived_at = None if exercise.archived_at else timezone.now()
    exercise.save(update_fields=["archived_at"])
    log.record(request, "archive" if exercise.archived_at else "restore", exercise)
    if exercise.archived_at:
        messages.success(
            request,
            f"{exercise.name} is archived: it is no longer offered for new recordings "
            "or prescriptions; its recordings and results stay.",
        )
    else:
        messages.success(request, f"{exercise.name} is offered again.")
    return redirect("exercises:detail", pk=exercise.pk)


@login_required
@require_staff
def replace_reference(request: HttpRequest, pk) -> HttpResponse:
    exercise = get_exercise_for_user(request, pk)
    form = ReferenceForm(request.POST or None, request.FILES or None)
    if request.method == "POST" and form.is_valid():
        services.replace_reference(exercise, form.parsed)
        log.record(request, "update", exercise)
        messages.success(request, replaced_message(exercise))
        return redirect("exercises:annotate", pk=exercise.pk)
    status = 400 if request.method == "POST" else 200
    context = {
        "form": form,
        "title": f"Replace the reference of {exercise.name}",
        "intro": "Key poses are suggested from the new reference for you to check. The model "
        "in use now stays in use until you save them; a new version is then built from them. "
        "Results of recordings already analysed keep the version they were made with.",
        "submit": "Replace the reference",
        "exercise": exercise,
    }
    return render(request, "exercises/form.html", context, status=status)


def replaced_message(exercise: Exercise) -> str:
    reading = (
        "The video is read first (about a minute for a minute of video); its key poses are then "
        "suggested here. "
        if exercise.tutor_is_video
        else "Key poses are suggested from it below. "
    )
    in_use = exercise.active_model
    keeps = f"model version {in_use.version} stays in use" if in_use else "no model is in use"
    return (
        f"New reference saved. {reading}Check them and save them: until then {keeps}; the key "
        "poses you save build the new version."
    )


@login_required
@require_staff
def reference_data(request: HttpRequest, pk) -> JsonResponse:
    """The reference's positions for the player on the exercise page."""
    exercise = get_exercise_for_user(request, pk)
    if not exercise.tutor_ready():  # never the pose estimator inside a request
        return JsonResponse({"message": READING_VIDEO}, status=409)
    motion = exercise.tutor_motion()
    pose = tutor_pose(motion)
    return JsonResponse(
        {
            "fps": motion.fps,
            "n_frames": int(motion.frames.shape[0]),
            "joints": len(motion.skeleton.names),
            "names": list(motion.skeleton.names),
            "parents": pose["parents"],
            "positions": pose["positions"],
        }
    )
