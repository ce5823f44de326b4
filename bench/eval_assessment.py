"""Evaluation of the assessment pipeline on UI-PRMD (subjects as folds).

Per exercise: the tutor is s01's correct session. Cold start: the model is built from the tutor
alone. Trained: for each test subject, the model is also trained (``--train``) with the labelled
sessions of the other subjects s02–s07 (leave one subject out). Reports ROC-AUC of the recording
score and of the per-repetition scores (each repetition labelled as its session) for correct vs
incorrect sessions, exact repetition counts, the share of true repetition starts found within
±5 frames, and the naive baseline (plain DTW distance of each repetition, cut at the true
boundaries, to the tutor's repetitions). Then the one calibrated scale (issue 17): the mean
recording score of correct and of incorrect sessions, the share of sessions whose pass/fail
(recording score against the result's pass threshold) agrees with the label, and the corrections
(the feedback's advice): sessions with at least one (incorrect) or at most one (correct).

    python -m bench.eval_assessment [--data data/ui-prmd] [--exercises m01,m02] [--no-trained]
"""

from __future__ import annotations

import argparse
import csv
import itertools
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from sklearn.metrics import roc_auc_score

from analysis.assessment.scoring import repetition_distance
from analysis.bvh import Motion, read
from analysis.kinematics import flatten, scaled_positions
from analysis.landmarks import KeyPoses
from analysis.pipeline import TrainingRecording, analyse, build_model

SUBJECTS = [f"s{k:02d}" for k in range(2, 8)]
# The figures of the pipeline before it ran the papers' stages (progress-axis segmentation, no
# key poses), measured with this script on 2026-11-23 at commit b6b61f4, to print beside today's.
BEFORE = {
    "cold start (tutor only)": {"AUC recording": 0.958, "AUC repetition": 0.879,
                                "exact count": 0.967, "starts ±5": 0.953},
    "trained (other subjects' labelled sessions)": {"AUC recording": 0.961, "AUC repetition": 0.912,
                                                    "exact count": 0.967, "starts ±5": 0.953},
}  # fmt: skip
LABELS = ("correct", "incorrect")


@dataclass
class Session:
    name: str
    subject: str
    correct: bool
    motion: Motion
    rep_starts: list[int]
    landmark_frames: list[int]
    landmark_types: list[int]


@dataclass
class ExerciseResult:
    recording_scores: list[tuple[float, bool]] = field(default_factory=list)
    rep_scores: list[tuple[float, bool]] = field(default_factory=list)
    baseline: list[tuple[float, bool]] = field(default_factory=list)
    counts_exact: int = 0
    sessions: int = 0
    starts_found: int = 0
    starts_total: int = 0
    seconds: float = 0.0
    fallbacks: int = 0
    unfit: int = 0  # sessions called "does not look like" the exercise (all are of it)
    agree: int = 0  # sessions whose pass/fail (score >= pass_threshold) matches the label
    thresholds: set[float] = field(default_factory=set)
    corrections: list[tuple[int, bool]] = field(default_factory=list)  # (count, is correct)


def load_sessions(data: Path, exercise: str) -> tuple[Session, list[Session]]:
    with open(data / "labels.csv") as a, open(data / "landmarks.csv") as b:
        labels = {r["file"]: r for r in csv.DictReader(a)}
        marks = {r["file"]: r for r in csv.DictReader(b)}

    def session(subject: str, label: str) -> Session:
        name = f"sessions/{exercise}_{subject}_{label}.bvh.gz"
        ints = lambda text: [int(v) for v in text.split(";")]  # noqa: E731
        return Session(
            name, subject, label == "correct", read(data / name),
            ints(labels[name]["rep_start_frames"]), ints(marks[name]["frames"]),
            ints(marks[name]["types"]),
        )  # fmt: skip

    tutor = session("s01", "correct")
    return tutor, [session(s, lab) for s in SUBJECTS for lab in LABELS]


def training_items(sessions: list[Session], exclude: str) -> list[TrainingRecording]:
    return [
        TrainingRecording(
            s.motion, KeyPoses.of(s.landmark_frames, s.landmark_types),
            "correct" if s.correct else "incorrect",
        )
        for s in sessions if s.subject != exclude
    ]  # fmt: skip


def naive_distances(tutor: Session, session: Session) -> list[float]:
    """Plain DTW distance of each true repetition to the tutor's true repetitions (all joints)."""
    joints = list(range(len(tutor.motion.skeleton.names)))

    def reps(s: Session) -> list[np.ndarray]:
        feats = flatten(scaled_positions(s.motion, joints))
        bounds = [*s.rep_starts, s.motion.n_frames]
        return [feats[a:b] for a, b in itertools.pairwise(bounds)]

    templates = reps(tutor)
    return [repetition_distance(r, templates) for r in reps(session)]


def evaluate_session(result: ExerciseResult, session: Session, model, tutor: Session) -> None:
    start = time.perf_counter()
    summary = analyse(session.motion, model).to_json()
    result.seconds += time.perf_counter() - start
    result.sessions += 1
    result.fallbacks += summary["segmentation"] == "fallback"
    found = [r["start"] for r in summary["repetitions"]]
    result.counts_exact += len(found) == len(session.rep_starts)
    for truth in session.rep_starts:
        result.starts_total += 1
        result.starts_found += bool(found) and min(abs(f - truth) for f in found) <= 5
    score = 0.0 if summary["score"] is None else summary["score"]  # None: does not fit
    result.unfit += not summary.get("match", {"fits": True})["fits"]
    result.recording_scores.append((score, session.correct))
    result.agree += (score >= summary["pass_threshold"]) == session.correct
    result.thresholds.add(summary["pass_threshold"])
    advice = summary.get("advice") or {}
    result.corrections.append((len(advice.get("corrections", ())), session.correct))
    result.rep_scores += [(r["score"], session.correct) for r in summary["repetitions"]]


def auc(pairs: list[tuple[float, bool]]) -> float:
    y = [c for _, c in pairs]
    return float(roc_auc_score(y, [s for s, _ in pairs])) if len(set(y)) == 2 else float("nan")


def run_exercise(data: Path, exercise: str, trained: bool) -> ExerciseResult:
    tutor, sessions = load_sessions(data, exercise)
    result = ExerciseResult()
    cold = build_model(tutor.motion, tutor.landmark_frames, tutor.landmark_types)
    for subject in SUBJECTS:
        model = cold
        if trained:
            model = build_model(
                tutor.motion, tutor.landmark_frames, tutor.landmark_types,
                training=training_items(sessions, subject),
            )  # fmt: skip
        for session in (s for s in sessions if s.subject == subject):
            evaluate_session(result, session, model, tutor)
            naive = naive_distances(tutor, session)
            result.baseline.append((-float(np.mean(naive)), session.correct))
    return result


def row(exercise: str, r: ExerciseResult) -> str:
    return (
        f"| {exercise} | {auc(r.recording_scores):.3f} | {auc(r.rep_scores):.3f} | "
        f"{auc(r.baseline):.3f} | {r.counts_exact}/{r.sessions} | "
        f"{r.starts_found / max(r.starts_total, 1):.3f} | {r.seconds / max(r.sessions, 1):.3f} |"
    )


def table(data: Path, exercises: list[str], trained: bool) -> list[ExerciseResult]:
    title = "trained (other subjects' labelled sessions)" if trained else "cold start (tutor only)"
    print(f"\n### {title}\n")
    print("| exercise | AUC recording | AUC repetition | AUC naive DTW | exact count | "
          "starts ±5 | s/session |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    results = []
    for exercise in exercises:
        results.append(run_exercise(data, exercise, trained))
        print(row(exercise, results[-1]), flush=True)
    rec = np.nanmean([auc(r.recording_scores) for r in results])
    rep = np.nanmean([auc(r.rep_scores) for r in results])
    base = np.nanmean([auc(r.baseline) for r in results])
    exact = sum(r.counts_exact for r in results) / sum(r.sessions for r in results)
    starts = sum(r.starts_found for r in results) / sum(r.starts_total for r in results)
    print(f"| **mean** | {rec:.3f} | {rep:.3f} | {base:.3f} | {exact:.3f} | {starts:.3f} | |")
    fallbacks = sum(r.fallbacks for r in results)
    print(f"\nFallback segmentation (no key-pose cycle): {fallbacks} of "
          f"{sum(r.sessions for r in results)} sessions; called \"does not look like\" the "
          f"exercise: {sum(r.unfit for r in results)}.")  # fmt: skip
    calibration_figures(results)
    now = {"AUC recording": rec, "AUC repetition": rep, "exact count": exact, "starts ±5": starts}
    before = BEFORE[title]
    print("\n| figure | before (b6b61f4) | now |\n|---|---|---|")
    for name, value in now.items():
        print(f"| {name} | {before[name]:.3f} | {value:.3f} |")
    return results


def calibration_figures(results: list[ExerciseResult]) -> None:
    """The one scale's figures over all exercises (issue 17's targets)."""
    pairs = [p for r in results for p in r.recording_scores]
    good = np.mean([s for s, c in pairs if c])
    bad = np.mean([s for s, c in pairs if not c])
    sessions = sum(r.sessions for r in results)
    agree = sum(r.agree for r in results) / sessions
    thresholds = sorted(set().union(*(r.thresholds for r in results)))
    counts = [p for r in results for p in r.corrections]
    flagged = np.mean([n >= 1 for n, c in counts if not c])
    quiet = np.mean([n <= 1 for n, c in counts if c])
    most = max(n for n, _ in counts)
    print(f"\nOne scale: pass threshold(s) {thresholds}; mean recording score correct {good:.1f}, "
          f"incorrect {bad:.1f} (gap {good - bad:.1f} points); pass/fail agrees with the label "
          f"on {agree:.1%} of {sessions} sessions.")  # fmt: skip
    for r, name in zip(results, EXERCISES, strict=False):
        print(f"  {name}: agree {r.agree}/{r.sessions}")
    print(f"Corrections: incorrect sessions with at least one {flagged:.1%}; correct sessions "
          f"with at most one {quiet:.1%}; at most {most} per recording.")  # fmt: skip


EXERCISES: list[str] = []


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=Path("data/ui-prmd"))
    parser.add_argument("--exercises", default=",".join(f"m{k:02d}" for k in range(1, 11)))
    parser.add_argument("--no-trained", action="store_true")
    parser.add_argument("--no-cold", action="store_true")
    args = parser.parse_args()
    exercises = args.exercises.split(",")
    EXERCISES[:] = exercises
    print(f"UI-PRMD assessment evaluation, {time.strftime('%Y-%m-%d')}")
    if not args.no_cold:
        table(args.data, exercises, trained=False)
    if not args.no_trained:
        table(args.data, exercises, trained=True)


if __name__ == "__main__":
    main()
