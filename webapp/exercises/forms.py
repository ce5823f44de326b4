from __future__ import annotations

from django import forms
from django.core.exceptions import ValidationError

from webapp.exercises.models import Exercise
from webapp.recordings.uploads import ParsedUpload, parse_upload, recording_size

# A reference may come from any source a recording may (webapp.recordings.forms.UploadForm).
REFERENCE_HELP = (
    "A recording of the exercise done well: BVH (.bvh, .bvh.gz), Kinect joint positions (.csv), "
    "Azure Kinect or MediaPipe (.json), .trc or .c3d; or a phone video (.mp4, .mov, .webm) of "
    "the whole body, which the system takes about a minute to read."
)
REFERENCE_WIDGET = forms.ClearableFileInput(
    attrs={"accept": ".bvh,.gz,.csv,.txt,.json,.trc,.c3d,.mp4,.mov,.webm"}
)


def parse_int_list(text: str, field: str) -> list[int]:
    try:
        return [int(part) for part in text.replace(",", ";").split(";") if part.strip()]
    except ValueError as error:
        raise ValidationError(f"{field}: use whole numbers separated by ';'.") from error


class ExerciseForm(forms.ModelForm):
    """Create an exercise from its tutor recording (the reference performance).

    Key poses are marked on the key-pose page, on a chart of the movement; the two hidden fields
    still take them from a script that knows their frames (the demo, tests)."""

    tutor = forms.FileField(
        label="The reference", help_text=REFERENCE_HELP, widget=REFERENCE_WIDGET
    )
    landmark_frames = forms.CharField(required=False, widget=forms.HiddenInput)
    landmark_types = forms.CharField(required=False, widget=forms.HiddenInput)

    class Meta:
        model = Exercise
        fields = ["name", "description"]
        labels = {"name": "Name", "description": "Instructions for the patient"}

    def __init__(self, *args, clinic, **kwargs):
        super().__init__(*args, **kwargs)
        self.clinic = clinic
        self.parsed: ParsedUpload | None = None

    def clean_name(self):
        name = self.cleaned_data["name"].strip()
        if Exercise.objects.filter(clinic=self.clinic, name__iexact=name).exists():
            raise ValidationError("Your clinic already has an exercise with this name.")
        return name

    def clean_tutor(self):
        upload = self.cleaned_data["tutor"]
        self.parsed = parse_upload(upload, any_source=True)
        return upload

    def clean(self):
        cleaned = super().clean()
        frames = parse_int_list(cleaned.get("landmark_frames", ""), "Key-pose frames")
        types = parse_int_list(cleaned.get("landmark_types", ""), "Key-pose types")
        validate_landmarks(frames, types, self.parsed)
        cleaned["frames_list"], cleaned["types_list"] = frames, types
        return cleaned


def validate_landmarks(frames: list[int], types: list[int], parsed: ParsedUpload | None) -> None:
    if len(frames) != len(types):
        raise ValidationError("Give one key-pose type for every key-pose frame.")
    if frames != sorted(frames):
        raise ValidationError("Key-pose frames must be in time order.")
    # A video's frame count comes from its header (the worker reads its frames later).
    n_frames = recording_size(parsed)[0] if parsed is not None else None
    if n_frames is not None and frames and (frames[0] < 0 or frames[-1] >= n_frames):
        raise ValidationError(f"Key-pose frames must lie between 0 and {n_frames - 1}.")
    if any(t < 1 for t in types):
        raise ValidationError("Key-pose types are numbered from 1.")


class LandmarksForm(forms.Form):
    """Edit the tutor's key poses (the annotation page posts this)."""

    frames = forms.CharField(required=False)
    types = forms.CharField(required=False)
    type_names = forms.JSONField(required=False)
    involved_joints = forms.JSONField(required=False)

    def __init__(self, *args, n_frames: int, joint_names: tuple[str, ...], **kwargs):
        super().__init__(*args, **kwargs)
        self.n_frames = n_frames
        self.joint_names = joint_names

    def clean(self):
        cleaned = super().clean()
        frames = parse_int_list(cleaned.get("frames") or "", "Key-pose frames")
        types = parse_int_list(cleaned.get("types") or "", "Key-pose types")
        if frames and (frames[0] < 0 or max(frames) >= self.n_frames):
            raise ValidationError(f"Key-pose frames must lie between 0 and {self.n_frames - 1}.")
        order = sorted(range(len(frames)), key=frames.__getitem__)
        cleaned["frames_list"] = [frames[i] for i in order]
        cleaned["types_list"] = [types[i] for i in order] if len(types) == len(frames) else types
        validate_landmarks(cleaned["frames_list"], cleaned["types_list"], None)
        if len(frames) < 2 or 1 not in types:
            raise ValidationError("Mark at least two key poses, including type 1 (start).")
        joints = cleaned.get("involved_joints") or []
        unknown = sorted(set(joints) - set(self.joint_names))
        if unknown:
            raise ValidationError(f"Unknown joints: {', '.join(unknown)}.")
        return cleaned


class ExerciseEditForm(forms.ModelForm):
    """Rename an exercise or change its instructions."""

    class Meta:
        model = Exercise
        fields = ["name", "description"]
        labels = {"name": "Name", "description": "Instructions for the patient"}

    def clean_name(self):
        name = self.cleaned_data["name"].strip()
        others = Exercise.objects.filter(clinic=self.instance.clinic_id, name__iexact=name)
        if others.exclude(pk=self.instance.pk).exists():
            raise ValidationError("Your clinic already has an exercise with this name.")
        return name


class ReferenceForm(forms.Form):
    """A new reference recording for an exercise."""

    tutor = forms.FileField(
        label="The new reference", help_text=REFERENCE_HELP, widget=REFERENCE_WIDGET
    )

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.parsed: ParsedUpload | None = None

    def clean_tutor(self):
        upload = self.cleaned_data["tutor"]
        self.parsed = parse_upload(upload, any_source=True)
        return upload
