"""What an audit event's object was, in the words a clinic admin reads ("recording of Ann
Example — Deep squat, 3 Nov 2026"), written with the event: the row keeps saying what was seen
even after the recording is moved to another patient or the patient is renamed."""

from __future__ import annotations

from django.core.exceptions import ObjectDoesNotExist
from django.utils import timezone
from django.utils.formats import date_format

MAX_LENGTH = 300
# Objects whose event needs no more than their kind (the patient column names whose data it is).
KIND_WORDS = {
    "Patient": "patient record",
    "Recording": "recording",
    "AnalysisRun": "analysis",
    "LandmarkCorrection": "key pose correction",
    "AssessmentCorrection": "assessment correction",
    "RepetitionLabel": "repetition label",
    "Prescription": "prescription",
    "PerformanceLevel": "performance level",
    "Invitation": "invitation",
    "User": "account",
    "Goal": "goal",
    "RecordingNote": "clinical note",
    "LiveSession": "live session",
}


def kind_words(object_type: str) -> str:
    return KIND_WORDS.get(object_type, object_type.lower())


def recording_words(recording) -> str:
    exercise = recording.exercise.name if recording.exercise_id else "exercise not confirmed"
    day = date_format(timezone.localtime(recording.uploaded_at), "j M Y")
    return f"recording of {recording.patient.display_name} — {exercise}, {day}"


def object_words(obj) -> str:
    kind = type(obj).__name__
    if kind == "Recording":
        return recording_words(obj)
    if kind == "Patient":
        return f"patient record of {obj.display_name}"
    if kind == "AnalysisRun":
        return f"analysis of the {recording_words(obj.recording)}"
    if hasattr(obj, "run_id"):  # corrections and labels of one run
        return f"{kind_words(kind)} on the {recording_words(obj.run.recording)}"
    if kind == "User":
        return f"account of {obj.get_full_name() or obj.get_username()}"
    name = getattr(obj, "name", "")  # an exercise, a clinic: the name the admin knows it by
    return f"{kind_words(kind)} “{name}”" if isinstance(name, str) and name else kind_words(kind)


def describe(obj) -> str:
    """What `obj` is, in words; its kind alone when a related row is already gone (a delete
    that cascades) or there is no object."""
    if obj is None:
        return ""
    try:
        return object_words(obj)[:MAX_LENGTH]
    except ObjectDoesNotExist:
        return kind_words(type(obj).__name__)
