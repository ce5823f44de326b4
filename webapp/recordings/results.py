"""The data of a results page: what the analysis found, in one JSON object.

The visual parts (3D playback, charts) read this through `recordings:result` and the API; it holds
repetitions with scores and guidance, the assessment per landmark and joint (with landmark type
names), feedback sentences, metrics, γ per joint and the most similar earlier recordings.
"""

from __future__ import annotations

from typing import Any

from analysis.assessment.scoring import PASS_SCORE
from analysis.pipeline import AnalysisSummary
from analysis.pipeline.results import assessment_to_json
from webapp.accounts.models import User
from webapp.recordings import similar
from webapp.recordings.models import AnalysisRun, Recording, RunStatus
from webapp.recordings.words import key_pose_name


def named_assessment(result: AnalysisSummary, names: dict[str, str]) -> list[dict[str, Any]]:
    return [
        {**assessment_to_json(item), "type_name": key_pose_name(item.type, names)}
        for item in result.assessment
    ]


def with_verdicts(result: AnalysisSummary) -> list[dict[str, Any]]:
    """Each repetition with `passed` by the one threshold (`PASS_SCORE`, 70 on every exercise:
    therapist verdicts train the model, they do not move the threshold)."""
    return [{**rep.to_json(), "passed": rep.score >= PASS_SCORE} for rep in result.repetitions]


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
    names = recording.exercise.landmark_type_names if recording.exercise else {}
    body.update(
        model_version=run.model.version if run.model_id else None,
        code_version=run.code_version,
        repetitions=with_verdicts(result),
        pass_threshold=PASS_SCORE,
        landmarks=[mark.to_json() for mark in result.landmarks],
        assessment=named_assessment(result, names),
        feedback=[comment.to_dict() for comment in result.feedback],
        metrics=metrics(result),
        gamma=dict(result.gamma),
        similar=similar.most_similar(recording, user),
    )
    return body
