"""Confirming the exercise of a recording uploaded without one.

A worker recognises the exercise (`workers/recognition.py`) while the recording page shows its
progress (through the status endpoint); the uploader then confirms the suggestion or chooses
another of the patient's prescribed exercises, and only that starts the analysis.
"""

from __future__ import annotations

from django import forms
from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.db.models import QuerySet
from django.http import HttpRequest, HttpResponse
from django.shortcuts import redirect, render

from webapp.accounts.models import User
from webapp.accounts.permissions import get_recording_for_user, visible_exercises
from webapp.exercises.models import Exercise
from webapp.recordings import services
from webapp.recordings.models import RecognitionState, Recording
from webapp.recordings.prescribed import offered_exercises
from webapp.recordings.recovery import analysable
from webapp.recordings.storage import DamagedRecordingError, read_verified
from webapp.recordings.uploads import check_skeleton, stored_motion

UNDER_WAY = (RecognitionState.QUEUED, RecognitionState.RUNNING)


class ConfirmForm(forms.Form):
    exercise = forms.ModelChoiceField(queryset=None, empty_label=None)

    def __init__(self, *args, recording, exercises, **kwargs):
        super().__init__(*args, **kwargs)
        self.recording = recording
        self.fields["exercise"].queryset = exercises

    def clean_exercise(self):
        exercise = self.cleaned_data["exercise"]
        try:
            content = read_verified(self.recording)
        except DamagedRecordingError as error:
            raise forms.ValidationError(str(error)) from error
        check_skeleton(stored_motion(self.recording.file.name, content), exercise)
        return exercise


def confirm_choices(user: User, recording: Recording) -> QuerySet[Exercise]:
    """The exercises offered for this recording: the patient's prescribed ones that can be
    analysed (every analysable exercise of the clinic when none is prescribed)."""
    return offered_exercises(recording.patient, analysable(visible_exercises(user))).order_by(
        "name"
    )


def confirm_form(user: User, recording: Recording, data=None) -> ConfirmForm:
    initial = {"exercise": recording.suggested_exercise_id}
    exercises = confirm_choices(user, recording)
    return ConfirmForm(data, initial=initial, recording=recording, exercises=exercises)


def suggestion_offered(form: ConfirmForm) -> Exercise | None:
    """The recognised exercise, when it is one the form offers (a one-click confirmation)."""
    suggested = form.recording.suggested_exercise
    if suggested is None or form.recording.recognition in UNDER_WAY:  # a new one is coming
        return None
    return suggested if form.fields["exercise"].queryset.filter(pk=suggested.pk).exists() else None


def recognition_status(recording: Recording) -> dict:
    """What the status endpoint answers for a recording with no analysis yet: how far the
    recognition of its exercise is."""
    return {
        "status": None,
        "stage": "",
        "progress": recording.recognition_progress,
        "recognition": recording.recognition,
    }


@login_required
def confirm(request: HttpRequest, pk) -> HttpResponse:
    """Confirm (or correct) the exercise the system recognised, then analyse the recording."""
    recording = get_recording_for_user(request, pk)
    if recording.exercise_id is not None:
        return redirect("recordings:detail", pk=recording.pk)
    form = confirm_form(request.user, recording, request.POST or None)
    if request.method == "POST" and form.is_valid():
        services.confirm_exercise(recording, form.cleaned_data["exercise"])
        messages.success(request, "Thank you. The analysis runs in the background: progress below.")
        return redirect("recordings:detail", pk=recording.pk)
    status = 400 if request.method == "POST" else 200
    context = {"recording": recording, "form": form, "suggested": suggestion_offered(form)}
    context["under_way"] = recording.recognition in UNDER_WAY
    return render(request, "recordings/confirm.html", context, status=status)
