"""The compare page: two analysed recordings of one patient side by side.

``/patients/{id}/compare/?a={recording id}&b={recording id}`` (a contract). Each side shows its
run's reading (`webapp.recordings.reading`): summary, per-repetition scores and verdicts, what to
correct, and the therapist's own corrections of the analysis; the clinical angles of both are
set in one table with the difference b − a. Without a or b the page offers two selects, b the
newest analysed recording and a the first one of the same exercise. Both recordings must be
the patient's (else 404).
"""

from __future__ import annotations

import uuid
from typing import Any

from django.contrib.auth.decorators import login_required
from django.db.models import QuerySet
from django.http import Http404, HttpRequest, HttpResponse
from django.shortcuts import render

from analysis.clinical.labels import angle_groups
from analysis.pipeline.results import AnalysisSummary
from webapp.accounts.permissions import get_patient_for_user, get_recording_for_user
from webapp.patients.models import Patient
from webapp.recordings.clinical import involved_joints
from webapp.recordings.models import Recording, RunStatus
from webapp.recordings.reading import reading_of


def analysed_recordings(patient: Patient) -> QuerySet[Recording]:
    """The patient's recordings with a finished analysis, oldest first."""
    return (
        patient.recordings.filter(runs__status=RunStatus.SUCCEEDED, exercise__isnull=False)
        .select_related("exercise")
        .distinct()
        .order_by("uploaded_at")
    )


def first_of_exercise(recording: Recording) -> Recording | None:
    """The patient's first analysed recording of the same exercise (perhaps this one)."""
    if recording.exercise_id is None:
        return None
    return analysed_recordings(recording.patient).filter(exercise=recording.exercise_id).first()


def default_pair(patient: Patient) -> tuple[Recording | None, Recording | None]:
    """(a, b): b the newest analysed recording, a the first one of b's exercise."""
    newest = analysed_recordings(patient).last()
    if newest is None:
        return None, None
    return first_of_exercise(newest), newest


def recording_of(request: HttpRequest, patient: Patient, pk: str) -> Recording:
    """The recording `pk` if it is this patient's (and visible to the user), else 404."""
    try:
        uuid.UUID(pk)
    except ValueError as error:
        raise Http404("No such recording.") from error
    recording = get_recording_for_user(request, pk)
    if recording.patient_id != patient.pk:
        raise Http404("No such recording for this patient.")
    return recording


def side_of(recording: Recording, letter: str) -> dict[str, Any]:
    """One side: the recording's newest succeeded run as its reading says it (verdicts with the
    therapist's labels first, the pass count, what to correct, what the therapist changed)."""
    run = recording.latest_succeeded_run()
    side: dict[str, Any] = {"letter": letter, "recording": recording, "run": run}
    reading = reading_of(run)
    if reading is None:
        return side
    said = reading.statements
    side.update(
        result=run.result,
        fits=reading.fits,
        score=reading.score,
        done=reading.repetition_count,
        passed=reading.passed_count,
        repetitions=[
            {"number": row["number"], "score": row["shown_score"], "passed": row["passed"]}
            for row in reading.repetitions
        ],
        to_correct=said.get("to_correct", []),
        therapist_changes=said.get("therapist", []),
    )
    return side


def repetition_rows(a: dict[str, Any], b: dict[str, Any]) -> list[dict[str, Any]]:
    """Repetition n of a beside repetition n of b (None where one has fewer)."""
    reps_a, reps_b = a.get("repetitions", []), b.get("repetitions", [])
    return [
        {
            "number": n + 1,
            "a": reps_a[n] if n < len(reps_a) else None,
            "b": reps_b[n] if n < len(reps_b) else None,
        }
        for n in range(max(len(reps_a), len(reps_b)))
    ]


def angle_comparison(
    result_a: AnalysisSummary | None, result_b: AnalysisSummary | None, joints: list[str]
) -> list[dict[str, Any]]:
    """The clinical angles of both by region (as the recording page groups them): per angle
    its range in a and in b (degrees) and the difference b − a, None where one lacks it."""
    angles_a = dict(result_a.clinical_angles) if result_a else {}
    angles_b = dict(result_b.clinical_angles) if result_b else {}
    groups = angle_groups({**angles_a, **angles_b}, joints)
    for group in groups:
        for row in group["rows"]:
            a, b = angles_a.get(row["name"]), angles_b.get(row["name"])
            row["a"], row["b"] = a, b
            row["difference"] = round(b.range - a.range, 2) if a and b else None
    return groups


def recording_choice(recording: Recording) -> dict[str, Any]:
    return {"pk": recording.pk, "when": recording.uploaded_at, "exercise": recording.exercise}


def comparison(recording_a: Recording, recording_b: Recording) -> dict[str, Any]:
    a, b = side_of(recording_a, "A"), side_of(recording_b, "B")
    joints = involved_joints(recording_a.exercise) + involved_joints(recording_b.exercise)
    return {
        "a": a,
        "b": b,
        "pair": [a, b],
        "same_exercise": recording_a.exercise_id == recording_b.exercise_id,
        "repetition_rows": repetition_rows(a, b),
        "angles": angle_comparison(a.get("result"), b.get("result"), joints),
    }


@login_required
def compare(request: HttpRequest, pk) -> HttpResponse:
    patient = get_patient_for_user(request, pk)
    chosen = {key: request.GET.get(key, "").strip() for key in ("a", "b")}
    picked = {key: recording_of(request, patient, value) for key, value in chosen.items() if value}
    default_a, default_b = default_pair(patient)
    selected_a, selected_b = picked.get("a", default_a), picked.get("b", default_b)
    context: dict[str, Any] = {
        "patient": patient,
        "choices": [recording_choice(r) for r in analysed_recordings(patient).reverse()],
        "selected_a": selected_a.pk if selected_a else None,
        "selected_b": selected_b.pk if selected_b else None,
    }
    if "a" in picked and "b" in picked:
        context.update(comparison(picked["a"], picked["b"]))
    return render(request, "patients/compare.html", context)
