from __future__ import annotations

from typing import Any

from django import forms
from django.core.exceptions import ValidationError

from webapp.accounts.models import User
from webapp.accounts.permissions import visible_exercises, visible_patients
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient
from webapp.recordings.models import Recording
from webapp.recordings.prescribed import prescribed_exercises
from webapp.recordings.recovery import analysable, check_analysable, check_move
from webapp.recordings.uploads import (
    ParsedUpload,
    check_not_duplicate,
    check_skeleton,
    parse_upload,
)

# The Borg CR10 scale, asked in the patient's words (the upload form and the result page).
EFFORT = {
    "label": "How hard did it feel? (0 = no effort at all, 10 = the hardest possible)",
    "help_text": "Borg CR10 scale, 0–10. Leave empty if you are not sure.",
}


class EffortForm(forms.ModelForm):
    """The effort of one session, given on its result page when the upload did not say it."""

    effort = forms.IntegerField(min_value=0, max_value=10, required=True, **EFFORT)

    class Meta:
        model = Recording
        fields = ["effort"]


class UploadForm(forms.Form):
    """Upload one recording. Validation parses the file, so a saved form is a usable recording."""

    patient = forms.ModelChoiceField(queryset=Patient.objects.none())
    exercise = forms.ModelChoiceField(
        queryset=Exercise.objects.none(),
        required=False,
        help_text=(
            "Leave empty to let the system recognise the exercise; you confirm its suggestion next."
        ),
    )
    file = forms.FileField(
        help_text=(
            "A motion-capture recording: BVH (.bvh, .bvh.gz), Kinect joint positions (.csv or "
            "the Kinect's own .txt), Azure Kinect, BlazePose or MediaPipe (.json), Vicon target "
            "text (.txt), .trc or .c3d; or a phone video (.mp4, .mov, .webm) of the whole body."
        ),
        widget=forms.ClearableFileInput(
            attrs={"accept": ".bvh,.gz,.csv,.txt,.json,.trc,.c3d,.mp4,.mov,.webm"}
        ),
    )
    pain_score = forms.IntegerField(
        min_value=0, max_value=10, required=False, label="Pain (0 = none, 10 = worst)"
    )
    effort = forms.IntegerField(min_value=0, max_value=10, required=False, **EFFORT)
    note = forms.CharField(
        widget=forms.Textarea(attrs={"rows": 3}), required=False, max_length=2000
    )

    def __init__(self, *args, patients, exercises, own_patient: Patient | None = None, **kwargs):
        super().__init__(*args, **kwargs)
        self.fields["patient"].queryset = patients
        self.fields["exercise"].queryset = exercises
        # A patient uploads for themselves: no list of patients to pick from.
        self.own_patient = own_patient
        if own_patient is None:
            del self.fields["effort"]  # how the session felt is the patient's own answer
        else:
            del self.fields["patient"]
            # A patient records with what the clinic gave them: no list of file formats.
            file_help = "The file of your session, as your recording app or camera saved it."
            self.fields["file"].help_text = file_help
            self.fields["exercise"].help_text = (
                "One of the exercises your therapist prescribed; leave empty to let the system "
                "recognise it."
            )
        self.parsed: ParsedUpload | None = None

    def clean_exercise(self):
        exercise = self.cleaned_data["exercise"]
        if exercise is not None:
            check_analysable(exercise)  # the API offers every exercise; say why not this one
        return exercise

    def clean_file(self):
        upload = self.cleaned_data["file"]
        self.parsed = parse_upload(upload, any_source=True)
        return upload

    def clean(self):
        cleaned = super().clean()
        if self.own_patient is not None:
            cleaned["patient"] = self.own_patient
        patient, exercise = cleaned.get("patient"), cleaned.get("exercise")
        if self.parsed is None or patient is None:
            return cleaned
        try:
            check_not_duplicate(patient, self.parsed.checksum)
            if exercise is not None:
                check_skeleton(self.parsed.motion, exercise)
        except ValidationError as error:
            self.add_error("file", error)
        if self.errors:
            # A refused upload's recording (up to the upload caps, tens of MB) is not needed: drop
            # it now. The form is a reference cycle, freed only when the cyclic collector runs.
            self.parsed = None
        return cleaned


def upload_choices(user: User) -> dict[str, Any]:
    """The UploadForm arguments for this user: staff pick any active patient of the clinic and any
    active exercise; a patient uploads for themselves only, one of the exercises prescribed to
    them (`own_patient`)."""
    patients = visible_patients(user).filter(archived_at__isnull=True)
    exercises = analysable(visible_exercises(user))  # none without key poses: not analysable
    if not user.is_patient:
        return {"patients": patients, "exercises": exercises}
    own = patients.first()
    if own is None:
        return {"patients": patients, "exercises": exercises.none(), "own_patient": None}
    prescribed = prescribed_exercises(own, exercises)  # current prescriptions only
    return {"patients": patients, "exercises": prescribed, "own_patient": own}


class MoveForm(forms.Form):
    """Move a recording to another exercise and/or patient of the clinic (the page and the API)."""

    exercise = forms.ModelChoiceField(
        queryset=Exercise.objects.none(),
        required=False,
        error_messages={"invalid_choice": "Unknown exercise: not one of the clinic's exercises."},
    )
    patient = forms.ModelChoiceField(
        queryset=Patient.objects.none(),
        required=False,
        error_messages={"invalid_choice": "Unknown patient: not one of the clinic's patients."},
    )

    def __init__(self, *args, recording: Recording, user: User, **kwargs):
        super().__init__(*args, **kwargs)
        self.recording = recording
        self.fields["exercise"].queryset = visible_exercises(user).filter(archived_at__isnull=True)
        self.fields["patient"].queryset = visible_patients(user).filter(archived_at__isnull=True)
        self.changes: dict[str, Any] = {}

    def offer_analysable_only(self) -> MoveForm:
        """The page lists only exercises a recording can be analysed against (the API answers
        why another one cannot be chosen)."""
        field = self.fields["exercise"]
        field.queryset = analysable(field.queryset)
        return self

    def clean(self):
        cleaned = super().clean()
        if self.errors:
            return cleaned
        exercise, patient = cleaned.get("exercise"), cleaned.get("patient")
        if exercise is None and patient is None:
            raise ValidationError("Choose the exercise or the patient to move the recording to.")
        self.changes = check_move(self.recording, exercise, patient)  # empty: nothing to do
        return cleaned
