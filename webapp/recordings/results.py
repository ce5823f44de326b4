"""The data of a results page: what the analysis found, in one JSON object.

The visual parts (3D playback, charts) read this through `recordings:result` and the API; it holds
repetitions with scores and guidance, the assessment per landmark and joint (with landmark type
names), feedback sentences, metrics, γ per joint and the most similar earlier recordings.
"""

from __future__ import annotations

from typing import Any

from webapp.accounts.models import User
from webapp.recordings import similar
from webapp.recordings.models import AnalysisRun, Recording, RunStatus

METRICS = ("score", "repetition_count", "tempo", "range_of_motion", "frames", "fps", "mirrored")


def named_assessment(summary: dict[str, Any], names: dict[str, str]) -> list[dict[str, Any]]:
    return [
        {**item, "type_name": names.get(str(item.get("type")), f"pose {item.get('type')}")}
        for item in summary.get("assessment", [])
    ]


def with_verdicts(repetitions: list[dict[str, Any]], recording: Recording) -> list[dict[str, Any]]:
    """Each repetition with `passed` by the exercise's 001 threshold (None until one is fitted)."""
    threshold = recording.exercise.pass_threshold if recording.exercise else None
    return [
        {**rep, "passed": None if threshold is None else rep.get("score", 0.0) >= threshold}
        for rep in repetitions
    ]


def result_data(recording: Recording, run: AnalysisRun | None, user: User) -> dict[str, Any]:
    body: dict[str, Any] = {
        "recording": str(recording.pk),
        "exercise": str(recording.exercise_id) if recording.exercise_id else None,
        "run": str(run.pk) if run else None,
        "status": run.status if run else None,
    }
    if run is None or run.status != RunStatus.SUCCEEDED:
        return body
    summary = run.summary or {}
    names = recording.exercise.landmark_type_names if recording.exercise else {}
    body.update(
        model_version=run.model.version if run.model_id else None,
        code_version=run.code_version,
        repetitions=with_verdicts(summary.get("repetitions", []), recording),
        pass_threshold=recording.exercise.pass_threshold if recording.exercise else None,
        landmarks=summary.get("landmarks", []),
        assessment=named_assessment(summary, names),
        feedback=summary.get("feedback", []),
        metrics={key: summary.get(key) for key in METRICS},
        gamma=summary.get("gamma", {}),
        similar=similar.most_similar(recording, user),
    )
    return body
