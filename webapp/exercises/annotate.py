"""Data and edits behind the tutor's key-pose annotation and grammar editing (JSON endpoints).

`tutor_data` gives the tutor's joint-angle curves (the rotation angle of every joint's local
rotation, degrees per frame) with the marked key poses and the key poses the system suggests (rest
and extreme poses), for the annotation page to draw; the page posts the edited key poses to
`save_landmarks`. `check_grammar` validates feedback-grammar text as
the therapist types (line and column of the first error) and saves it when asked.
"""

from __future__ import annotations

import json

import numpy as np
from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import render
from django.views.decorators.http import require_POST

from analysis.feedback import Grammar, GrammarError
from analysis.kinematics import rotations
from analysis.landmarks import suggest_key_poses
from webapp.accounts.permissions import get_exercise_for_user, require_staff
from webapp.exercises.forms import LandmarksForm
from webapp.exercises.models import Exercise


def angle_curves(motion) -> dict[str, list[float]]:
    """Per joint, the angle (deg) of its local rotation in every frame, rounded to 0.1°."""
    quats = rotations(motion)  # (F, J, 4) unit quaternions w, x, y, z
    angles = np.degrees(2.0 * np.arccos(np.clip(np.abs(quats[..., 0]), 0.0, 1.0)))
    return {
        name: np.round(angles[:, j], 1).tolist() for j, name in enumerate(motion.skeleton.names)
    }


@login_required
@require_staff
def annotate_page(request: HttpRequest, pk) -> HttpResponse:
    exercise = get_exercise_for_user(request, pk)
    return render(request, "exercises/annotate.html", {"exercise": exercise})


@login_required
@require_staff
def tutor_data(request: HttpRequest, pk) -> JsonResponse:
    exercise = get_exercise_for_user(request, pk)
    motion = exercise.tutor_motion()
    suggestion = suggest_key_poses(motion)
    return JsonResponse(
        {
            "fps": motion.fps,
            "n_frames": int(motion.frames.shape[0]),
            "joints": list(motion.skeleton.names),
            "angles_deg": angle_curves(motion),
            "landmark_frames": exercise.tutor_landmark_frames,
            "landmark_types": exercise.tutor_landmark_types,
            "type_names": exercise.landmark_type_names,
            "involved_joints": exercise.involved_joints,
            "suggested_frames": list(suggestion.frames),
            "suggested_types": list(suggestion.types),
        }
    )


@login_required
@require_staff
@require_POST
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
    names = data.get("type_names") or {}
    exercise.landmark_type_names = {
        str(t): str(names.get(str(t)) or f"key pose {t}") for t in sorted(set(data["types_list"]))
    }
    exercise.involved_joints = data.get("involved_joints") or []
    exercise.save()
    return JsonResponse({"saved": True, "landmark_frames": exercise.tutor_landmark_frames})


def grammar_verdict(text: str) -> dict:
    try:
        rules = Grammar.parse(text).rules
    except GrammarError as error:
        return {
            "valid": False,
            "message": error.message,
            "line": error.line,
            "column": error.column,
        }
    return {"valid": True, "rules": len(rules)}


@login_required
@require_staff
@require_POST
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
    verdict = grammar_verdict(text)
    if verdict["valid"] and body.get("save"):
        Exercise.objects.filter(pk=exercise.pk).update(feedback_grammar=text)
        verdict["saved"] = True
    return JsonResponse(verdict, status=200 if verdict["valid"] or not body.get("save") else 400)
