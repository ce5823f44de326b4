"""Data and edits behind the tutor's key-pose annotation and grammar editing (JSON endpoints).

`tutor_data` gives the tutor's joint-angle curves (the rotation angle of every joint's local
rotation, degrees per frame), the joints' anatomical names and their order by movement, the
tutor's positions for the 3D view, the marked key poses and the key poses the system suggests (rest
and extreme poses), for the annotation page to draw; the page posts the edited key poses and the
names typed for their kinds to `save_landmarks`. `check_grammar` validates feedback-grammar text as
the therapist types (line and column of the first error) and saves it when asked.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from functools import wraps

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import redirect, render
from django.urls import reverse
from django.views.decorators.http import require_POST

from analysis.feedback import GrammarError, check_names
from analysis.landmarks import suggest_key_poses
from webapp.accounts.permissions import get_exercise_for_user, require_staff
from webapp.audit import log
from webapp.exercises import services
from webapp.exercises.annotate_data import (
    angle_curves,
    default_grammar_text,
    grammar_has_findings,
    movement_order,
    older_names,
    plain_labels,
    tutor_pose,
    type_names,
    written_names,
)
from webapp.exercises.body_parts import offered, representatives, ticked
from webapp.exercises.forms import LandmarksForm
from webapp.exercises.models import Exercise
from webapp.exercises.rule_picker import RuleForm, appended

READING = (
    "The reference video is still being read (finding the person in each frame takes a minute "
    "or two). Its key poses and rules can be edited once the exercise page shows it."
)


def reference_read(view: Callable[..., HttpResponse]) -> Callable[..., HttpResponse]:
    """Answer 409 while a reference video waits for the worker: reading it here would hold the
    page for minutes."""

    @wraps(view)
    def checked(request: HttpRequest, pk) -> HttpResponse:
        if not get_exercise_for_user(request, pk).tutor_ready():
            return HttpResponse(READING, status=409, content_type="text/plain; charset=utf-8")
        return view(request, pk)

    return checked


__all__ = [
    "add_rule",
    "angle_curves",
    "annotate_page",
    "check_grammar",
    "save_landmarks",
    "tutor_data",
]


@login_required
@require_staff
@reference_read
def annotate_page(request: HttpRequest, pk) -> HttpResponse:
    """The page; an exercise with no grammar yet shows the one it would be given."""
    exercise = get_exercise_for_user(request, pk)
    motion = exercise.tutor_motion()
    form = RuleForm(exercise=exercise, skeleton=motion.skeleton)
    return render(request, "exercises/annotate.html", page_context(exercise, form))


def shown_grammar(exercise: Exercise) -> tuple[str, bool]:
    """The exercise's rules, or the default ones it would be given (and whether they are)."""
    if exercise.feedback_grammar.strip():
        return exercise.feedback_grammar, False
    motion = exercise.tutor_motion()
    order = movement_order(angle_curves(motion), tuple(motion.skeleton.names))
    return default_grammar_text(exercise, motion, order), True


def page_context(exercise: Exercise, form: RuleForm, grammar: str | None = None) -> dict:
    shown, is_default = shown_grammar(exercise)
    return {
        "exercise": exercise,
        "grammar": shown if grammar is None else grammar,
        "grammar_is_default": is_default and grammar is None,
        "findings": grammar_has_findings(),
        "rule_form": form,
    }


@login_required
@require_staff
@require_POST
@reference_read
def add_rule(request: HttpRequest, pk) -> HttpResponse:
    """The picked rule appended to the exercise's rules, saved when the whole text is valid."""
    exercise = get_exercise_for_user(request, pk)
    form = RuleForm(request.POST, exercise=exercise, skeleton=exercise.tutor_motion().skeleton)
    if form.is_valid() and already_there(shown_grammar(exercise)[0], form.rule_text()):
        form.add_error(None, "This rule is already in the feedback rules: nothing was added.")
    elif form.is_valid():
        text = appended(shown_grammar(exercise)[0], form.rule_text())
        verdict = grammar_verdict(text, exercise)
        if verdict["valid"]:
            Exercise.objects.filter(pk=exercise.pk).update(feedback_grammar=text)
            log.record(request, "update", exercise)
            messages.success(request, "Rule added to the feedback rules.")
            return redirect(reverse("exercises:annotate", args=[exercise.pk]) + "#grammar-editor")
        form.add_error(None, f"The rule could not be added: {verdict['message']}.")
    context = page_context(exercise, form)
    return render(request, "exercises/annotate.html", context, status=400)


@login_required
@require_staff
@reference_read
def tutor_data(request: HttpRequest, pk) -> JsonResponse:
    exercise = get_exercise_for_user(request, pk)
    motion = exercise.tutor_motion()
    suggestion = suggest_key_poses(motion)
    curves = angle_curves(motion)
    return JsonResponse(
        {
            "fps": motion.fps,
            "n_frames": int(motion.frames.shape[0]),
            "joints": list(motion.skeleton.names),
            # Anatomical names for the page: rig joint names are never shown.
            "labels": plain_labels(motion),
            # Each body part once (a rig's connector joints read as the part below them).
            "movement_order": offered(
                motion.skeleton, movement_order(curves, tuple(motion.skeleton.names))
            ),
            "body_parts": offered(motion.skeleton, motion.skeleton.names),
            "angles_deg": curves,
            "pose": tutor_pose(motion),
            "landmark_frames": exercise.tutor_landmark_frames,
            "landmark_types": exercise.tutor_landmark_types,
            "type_names": exercise.landmark_type_names,
            "involved_joints": ticked(motion.skeleton, exercise.involved_joints),
            "suggested_frames": suggestion.frames.tolist(),
            "suggested_types": suggestion.types.tolist(),
        }
    )


@login_required
@require_staff
@require_POST
@reference_read
def save_landmarks(request: HttpRequest, pk) -> JsonResponse:
    exercise = get_exercise_for_user(request, pk)
    motion = exercise.tutor_motion()
    form = LandmarksForm(
        request.POST, n_frames=motion.frames.shape[0], joint_names=tuple(motion.skeleton.names)
    )
    if not form.is_valid():
        return JsonResponse({"errors": form.errors.get_json_data()}, status=400)
    data = form.cleaned_data
    exercise.tutor_landmark_frames = data["frames_list"]
    exercise.tutor_landmark_types = data["types_list"]
    exercise.landmark_type_names = kept_type_names(
        data.get("type_names") or {}, exercise.landmark_type_names, data["types_list"]
    )
    chosen = representatives(motion.skeleton)
    exercise.involved_joints = sorted({chosen[j] for j in data.get("involved_joints") or []})
    exercise.save()
    log.record(request, "update", exercise)
    built = services.confirm_key_poses(exercise)  # a replaced reference's, once confirmed
    message = f"Saved. Model version {built.version} is being built from them." if built else ""
    return JsonResponse(
        {"saved": True, "landmark_frames": exercise.tutor_landmark_frames, "message": message}
    )


def kept_type_names(posted: dict, earlier: dict, types: list[int]) -> dict[str, str]:
    """The name of every kind of key pose marked: the one typed in, else the one it had, else
    "start" for kind 1 (others stay unnamed: pages describe them by their place)."""
    names = {}
    for kind in sorted(set(types)):
        typed = str((posted or {}).get(str(kind)) or "").strip()[:60]
        name = typed or str((earlier or {}).get(str(kind)) or "") or ("start" if kind == 1 else "")
        if name:
            names[str(kind)] = name
    return names


def grammar_verdict(text: str, exercise: Exercise) -> dict:
    """Whether the grammar parses and names only the exercise's body parts (in the words of the
    body-part ticks, or as older rules wrote them) and key-pose types; else the first problem
    with its line and column."""
    skeleton = exercise.tutor_motion().skeleton
    written = sorted(set(written_names(skeleton).values()))
    try:
        rules = check_names(text, written, type_names(exercise), also=older_names(skeleton))
    except GrammarError as error:
        return {
            "valid": False,
            "message": error.message,
            "line": error.line,
            "column": error.column,
        }
    return {"valid": True, "rules": len(rules)}


def already_there(grammar: str, rule: str) -> bool:
    """Whether the rule is already a line of the rules (spaces aside)."""
    squeeze = "".join
    return squeeze(rule.split()) in {squeeze(line.split()) for line in grammar.splitlines()}


@login_required
@require_staff
@require_POST
@reference_read
def check_grammar(request: HttpRequest, pk) -> JsonResponse:
    """POST {"text": ..., "save": bool}: the verdict; a valid text is stored when save is true."""
    exercise = get_exercise_for_user(request, pk)
    try:
        body = json.loads(request.body or b"{}")
        text = body["text"]
    except (json.JSONDecodeError, KeyError, TypeError):
        return JsonResponse({"detail": 'Send JSON {"text": "..."}.'}, status=400)
    if not isinstance(text, str):
        return JsonResponse({"detail": "text must be a string."}, status=400)
    verdict = grammar_verdict(text, exercise)
    if verdict["valid"] and body.get("save"):
        Exercise.objects.filter(pk=exercise.pk).update(feedback_grammar=text)
        log.record(request, "update", exercise)
        verdict["saved"] = True
    return JsonResponse(verdict, status=200 if verdict["valid"] or not body.get("save") else 400)
