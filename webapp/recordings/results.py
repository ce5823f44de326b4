"""The data of a results page: what the analysis found, in one JSON object.

Served by one view, the API's `/api/v1/recordings/{id}/result/` (`recordings:result`, the page's
`result.json`, answers through the same view). It holds the run's reading (`reading`: fits, score,
repetition and pass counts, what to correct; `webapp.recordings.reading`), repetitions with
scores, guidance, the reading's verdict and reasons, the assessment per landmark and joint (with
landmark type names), feedback sentences, metrics, γ per joint and the most similar earlier
recordings.
"""

from __future__ import annotations

from typing import Any

from analysis.pipeline import AnalysisSummary
from analysis.pipeline.results import assessment_to_json
from webapp.accounts.models import User
from webapp.recordings import similar
from webapp.recordings.models import AnalysisRun, Recording, RunReading, RunStatus
from webapp.recordings.reading import reading_of
from webapp.recordings.words import key_pose_name

STATEMENTS: dict[str, Any] = {"message": "", "to_correct": [], "went_well": [], "therapist": []}


def named_assessment(result: AnalysisSummary, names: dict[str, str]) -> list[dict[str, Any]]:
    return [
        {**assessment_to_json(item), "type_name": key_pose_name(item.type, names)}
        for item in result.assessment
    ]


def with_verdicts(result: AnalysisSummary, reading: RunReading) -> list[dict[str, Any]]:
    """Each repetition with the reading's verdict (the therapist's label first, then the
    analysis), who gave it, its sentence and its reasons."""
    return [
        {
            **rep.to_json(),
            "passed": row["passed"],
            "verdict_by": row["by"],
            "verdict": row["verdict"],
            "reasons": row["reasons"],
        }
        for rep, row in zip(result.repetitions, reading.repetitions, strict=True)
    ]


def reading_json(reading: RunReading) -> dict[str, Any]:
    """The reading's figures and statements (`webapp.recordings.reading`)."""
    return {
        "fits": reading.fits,
        "score": reading.score,
        "repetition_count": reading.repetition_count,
        "passed_count": reading.passed_count,
        "labelled_count": reading.labelled_count,
        **{key: reading.statements.get(key, default) for key, default in STATEMENTS.items()},
    }


def metrics(result: AnalysisSummary) -> dict[str, Any]:
    return {
        "score": result.score,
        "repetition_count": result.repetition_count,
        "tempo": result.tempo,
        "range_of_motion": dict(result.range_of_motion),
        "frames": result.frames,
        "fps": result.fps,
        "mirrored": result.mirrored,
        "match": result.match.to_json(),
    }


def result_data(recording: Recording, run: AnalysisRun | None, user: User) -> dict[str, Any]:
    body: dict[str, Any] = {
        "recording": str(recording.pk),
        "exercise": str(recording.exercise_id) if recording.exercise_id else None,
        "run": str(run.pk) if run else None,
        "status": run.status if run else None,
    }
    if run is None or run.status != RunStatus.SUCCEEDED:
        return body
    result = run.result or AnalysisSummary.from_json({})
    reading = reading_of(run)
    names = recording.exercise.landmark_type_names if recording.exercise else {}
    body.update(
        model_version=run.model.version if run.model_id else None,
        code_version=run.code_version,
        repetitions=with_verdicts(result, reading) if reading else [],
        reading=reading_json(reading) if reading else None,
        pass_threshold=result.pass_threshold,
        landmarks=[mark.to_json() for mark in result.landmarks],
        assessment=named_assessment(result, names),
        feedback=[comment.to_dict() for comment in result.feedback],
        metrics=metrics(result),
        gamma=dict(result.gamma),
        similar=similar.most_similar(recording, user),
    )
    return body
