"""What the training report of one exercise model says, in plain words for the therapist.

Reads the ``training_report`` stored with the model row (``analysis.pipeline`` builds it). Models
built before the papers' stages lack most keys: every entry is None when its key is missing.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from typing import Any

from analysis.feedback.text import joint_label
from webapp.exercises.models import ExerciseModel

log = logging.getLogger(__name__)

# How each method finds key poses, said without the method's name (therapists read this page).
CLASSIFIERS = {
    "c45": "a chain of yes/no questions about the body's pose, learnt from the reference",
    "svm": "a dividing line between the kinds of pose, learnt from the reference",
    "nb": "the odds of each kind of pose, learnt from the reference",
}
CLUSTERING = {
    "em": "grouped by how likely they belong together",
    "kmeans": "grouped around their average moments",
    "tc": "grouped by their spacing in time",
    "gap": "grouped wherever they are far apart in time",
}
SELECTION = {
    "mu1": "keeping the frame closest to the reference's pose of its own kind",
    "mu2": "keeping the frame of the group's main kind closest to the reference",
    "extreme": "keeping the frame that goes farthest",
}
# joint names read from model files, by model row (a file never changes once built)
_joint_names: dict[str, list[str]] = {}


def classifier_words(text: str) -> str:
    """'c45 + AdaBoost' -> 'a chain of yes/no questions …, several of them voting together'."""
    name, _, boost = str(text).partition(" + ")
    words = CLASSIFIERS.get(name.strip(), "a method learnt from the reference")
    return f"{words}, several of them voting together" if boost else words


def refining_words(text: str) -> str:
    """'gap clustering, mu1 selection' -> plain words for both choices (a method this page does
    not know is left out rather than named)."""
    parts = [p.strip().split(" ")[0] for p in str(text).split(",")]
    clustering = CLUSTERING.get(parts[0], "") if parts else ""
    selection = SELECTION.get(parts[1], "") if len(parts) > 1 else ""
    said = ", ".join(p for p in (clustering, selection) if p)
    return f"Moments that look alike are {said}" if said else "Moments that look alike are merged"


def pattern_words(pattern: Sequence[Any], names: Mapping[str, str]) -> str:
    return " → ".join(names.get(str(t), f"key pose {t}") for t in pattern)


def threshold_words(data: Mapping[str, Any]) -> dict[str, Any]:
    source = str(data.get("source", ""))
    how = (
        "set from labelled recordings"
        if source.startswith("labelled")
        else "set from the reference's own variation"
    )
    return {"value": round(float(data.get("value", 0.0))), "how": how}


def scorer_words(report: Mapping[str, Any]) -> str | None:
    scorer = report.get("scorer")
    if not isinstance(scorer, Mapping):
        return None
    trained = str(scorer.get("source", "")).startswith("labelled")
    basis = (
        "is trained on the therapist's labelled recordings, checked against the reference"
        if trained
        else "compares each repetition with how much the reference's own repetitions differ"
    )
    joints = scorer.get("joints")
    return f"The score {basis}" + (f" ({joints} body parts)." if joints else ".")


def involved_joint_names(row: ExerciseModel, count: int) -> list[str]:
    """The model's involved joints, in order: from the report, the exercise or the model file."""
    for names in (row.training_report.get("involved_joints"), row.exercise.involved_joints):
        if names and len(names) == count:
            return [str(n) for n in names]
    key = str(row.pk)
    if key not in _joint_names and row.artefact:
        from analysis.pipeline import load_model  # the numerical core only when needed

        try:
            with row.artefact.open("rb") as handle:
                _joint_names[key] = list(load_model(handle).involved_joints)
        except (OSError, ValueError, EOFError, AttributeError, ImportError) as error:
            log.warning("model %s: no joint names (%s)", key, error)
            _joint_names[key] = []
    names = _joint_names.get(key, [])
    return names if len(names) == count else [f"joint {i + 1}" for i in range(count)]


def joint_weights(row: ExerciseModel) -> list[dict[str, Any]] | None:
    weights = row.training_report.get("joint_weights")
    if not weights:
        return None
    names = involved_joint_names(row, len(weights))
    return [
        {"name": joint_label(n) if not n.startswith("joint ") else n, "weight": float(w)}
        for n, w in zip(names, weights, strict=True)
    ]


def key_poses(report: Mapping[str, Any], names: Mapping[str, str]) -> dict[str, Any] | None:
    data = report.get("key_poses")
    if not isinstance(data, Mapping):
        return None
    return {
        "classifier": classifier_words(data["classifier"]) if data.get("classifier") else None,
        "refining": refining_words(data["refining"]) if data.get("refining") else None,
        "patterns": [pattern_words(p, names) for p in data.get("periodic_patterns") or ()],
        "precision": percent(data.get("cross_validated_precision")),
    }


def percent(value: Any) -> float | None:
    return None if value is None else round(100.0 * float(value), 1)


def training_report(row: ExerciseModel) -> dict[str, Any]:
    """Plain-word entries of the model's report; missing entries are None."""
    report = row.training_report or {}
    names = {str(k): str(v) for k, v in (row.exercise.landmark_type_names or {}).items()}
    error = report.get("alignment_error")
    threshold = report.get("pass_threshold")
    return {
        "key_poses": key_poses(report, names),
        "joint_weights": joint_weights(row),
        "alignment_error": (
            {"before": percent(error.get("before")), "after": percent(error.get("after"))}
            if isinstance(error, Mapping)
            else None
        ),
        "pass_threshold": threshold_words(threshold) if isinstance(threshold, Mapping) else None,
        "scorer": scorer_words(report),
        "tutor_repetitions": report.get("tutor_repetitions"),
        "labelled_repetitions": report.get("labelled_repetitions"),
        "empty": not report,
    }
