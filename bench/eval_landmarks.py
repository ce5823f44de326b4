"""Landmark identification and refining on UI-PRMD (paper 004, section 5.6; issue 4 item 8).

Protocol: per exercise, leave one subject out over s01–s07. The tutor is s01 "correct" (s02
"correct" when s01 is the test subject, so no fold ever trains on its test subject). The PCA of
the signature is fitted on the tutor only. The classifier trains on
  - protocol "loso":  the tutor + both sessions (correct, incorrect) of the 5 or 6 other subjects;
  - protocol "tutor": the tutor alone (cold start) plus ``--augment`` warped copies of it.
Test: both sessions of the left-out subject (14 sessions per exercise, 140 in all). Ground truth:
landmarks.csv (type 1 start, type 2 end of range); compromise intervals (eq 5.34, Δ_Λ = 0.15) on
the root-relative, heading-normalised positions of all joints, smoothed over 5 frames. Baseline:
the tutor's landmarks carried over an offline DTW path on the involved joints (Table 5.8).

    .venv/bin/python -m bench.eval_landmarks                # DTW + faithful + ours, both protocols
    .venv/bin/python -m bench.eval_landmarks --ablation     # + faithful → ours one step at a time
    .venv/bin/python -m bench.eval_landmarks --grid --configs faithful --protocols loso
                                                            # + Table 5.5's 36-cell grid (slow)
    .venv/bin/python -m bench.eval_landmarks --quick        # m01, m07, test subjects s02, s04, s06

Timings (s/session) cover signature, identification, refining and periodic analysis of one
loaded recording (BVH parsing excluded), measured with time.perf_counter.
"""

from __future__ import annotations

import argparse
import ast
import csv
import platform
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from analysis.bvh import Motion, read
from analysis.dtw import DTWOptions, align
from analysis.kinematics import normalised_positions
from analysis.landmarks.detector import ClassifierName
from analysis.landmarks.evaluation import Confusion, compromise_intervals, confusion
from analysis.landmarks.identification import (
    FAITHFUL,
    LandmarkModel,
    LandmarkOptions,
    periodic_landmarks,
    tutor_cycle,
)
from analysis.landmarks.key_poses import KeyPoses
from analysis.landmarks.refining import Clustering, Selection, refine
from analysis.landmarks.regularise import GrammarOptions
from analysis.landmarks.repetitions import repetitions
from analysis.landmarks.signature import MotionSignature

EXERCISES = tuple(f"m{i:02d}" for i in range(1, 11))
SUBJECTS = tuple(f"s{i:02d}" for i in range(1, 8))
DELTA = 0.15


@dataclass(frozen=True)
class Session:
    name: str
    exercise: str
    subject: str
    motion: Motion
    frames: np.ndarray
    types: np.ndarray
    rep_count: int
    intervals: np.ndarray  # (n, 2) compromise intervals of the ground truth


@dataclass(frozen=True)
class Config:
    """A landmark configuration evaluated under one protocol."""

    name: str
    options: LandmarkOptions
    protocol: str = "loso"
    periodic: bool = True  # run analysis.periodic.clean (GA^K) on the landmarks


CONFIGS = {
    "faithful": Config("faithful: C4.5+AB+EM+μ1", FAITHFUL),
    "ours": Config("ours: default LandmarkOptions()", LandmarkOptions()),
}


def truth_positions(motion: Motion) -> np.ndarray:
    """(F, J·3) positions for the compromise intervals, averaged over 5 frames as in the ground
    truth rule, so that one frame of Kinect jitter does not end an interval."""
    data = normalised_positions(motion).reshape(motion.n_frames, -1)
    padded = np.pad(data, ((2, 2), (0, 0)), mode="edge")
    return np.asarray(sum(padded[k : k + len(data)] for k in range(5)) / 5.0)


def load_sessions(root: Path, exercise: str) -> list[Session]:
    with open(root / "landmarks.csv") as a, open(root / "labels.csv") as b:
        marks = {r["file"]: r for r in csv.DictReader(a)}
        labels = {r["file"]: r for r in csv.DictReader(b)}
    out = []
    for subject in SUBJECTS:
        for label in ("correct", "incorrect"):
            key = f"sessions/{exercise}_{subject}_{label}.bvh.gz"
            motion = read(root / key)
            frames = np.array(marks[key]["frames"].split(";"), dtype=np.int64)
            types = np.array(marks[key]["types"].split(";"), dtype=np.int64)
            intervals = compromise_intervals(truth_positions(motion), frames, DELTA)
            out.append(
                Session(
                    key,
                    exercise,
                    subject,
                    motion,
                    frames,
                    types,
                    int(labels[key]["rep_count"]),
                    intervals,
                )
            )
    return out


def split(
    sessions: list[Session], test: str, protocol: str
) -> tuple[Session, list[Session], list[Session]]:
    """(tutor, other training sessions, test sessions) of one fold."""
    tutor_subject = "s02" if test == "s01" else "s01"
    tutor = next(
        s for s in sessions if s.subject == tutor_subject and s.name.endswith("_correct.bvh.gz")
    )
    tests = [s for s in sessions if s.subject == test]
    if protocol == "tutor":
        return tutor, [], tests
    return tutor, [s for s in sessions if s.subject != test and s is not tutor], tests


@dataclass(frozen=True)
class Outcome:
    """One test session: confusions after identification, refining and the final stage."""

    session: Session
    identified: Confusion
    refined: Confusion
    final: Confusion
    reps: int
    seconds: float


def _score(s: Session, c: KeyPoses) -> Confusion:
    return confusion(c.frames, c.types, s.types, s.intervals, s.motion.n_frames)


def periodic_clean(c: KeyPoses, patterns: list[list[int]]) -> KeyPoses:
    """Chapter 6 (analysis.periodic.clean, GA^K): drop out-of-sequence landmarks."""
    return periodic_landmarks(c, patterns, method="ga-k", seed=0)


def count_repetitions(c: KeyPoses, cycle: list[int], n_frames: int) -> int:
    """Repetitions in a landmark sequence (analysis.repetitions, every one it returns)."""
    return len(repetitions(c.frames.tolist(), c.types.tolist(), cycle, last_frame=n_frames - 1))


def run_session(config: Config, model: LandmarkModel, s: Session) -> Outcome:
    start = time.perf_counter()
    result = model.detect(s.motion)
    final = (
        periodic_clean(result.landmarks, model.patterns_) if config.periodic else result.landmarks
    )
    seconds = time.perf_counter() - start
    return Outcome(
        s,
        _score(s, result.candidates),
        _score(s, result.refined),
        _score(s, final),
        count_repetitions(final, model.cycle_, s.motion.n_frames),
        seconds,
    )


def run_config(
    config: Config, data: dict[str, list[Session]], subjects: tuple[str, ...]
) -> list[Outcome]:
    outcomes = []
    for sessions in data.values():
        for test in subjects:
            tutor, train, tests = split(sessions, test, config.protocol)
            training = [(s.motion, s.frames, s.types) for s in train]
            model = LandmarkModel(options=config.options)
            model.fit(tutor.motion, tutor.frames, tutor.types, training)
            outcomes += [run_session(config, model, s) for s in tests]
    return outcomes


def dtw_transfer(tutor: Session, motion: Motion, joints: tuple[int, ...]) -> KeyPoses:
    """Table 5.8's DTW: each tutor landmark goes to the mean performance frame matched to it."""
    x = normalised_positions(tutor.motion)[:, list(joints)].reshape(tutor.motion.n_frames, -1)
    y = normalised_positions(motion)[:, list(joints)].reshape(motion.n_frames, -1)
    path = np.asarray(align(x, y, DTWOptions()).path)
    frames = np.array([round(path[path[:, 0] == f, 1].mean()) for f in tutor.frames])
    return KeyPoses(frames.astype(np.int64), tutor.types.astype(np.int64))


def run_dtw(data: dict[str, list[Session]], subjects: tuple[str, ...]) -> list[Outcome]:
    outcomes = []
    for sessions in data.values():
        for test in subjects:
            tutor, _, tests = split(sessions, test, "tutor")
            joints = MotionSignature(options=FAITHFUL.signature).fit(tutor.motion).joints_
            cycle = tutor_cycle(tutor.types)
            for s in tests:
                start = time.perf_counter()
                c = dtw_transfer(tutor, s.motion, joints)
                seconds = time.perf_counter() - start
                score = _score(s, c)
                reps = count_repetitions(c, cycle, s.motion.n_frames)
                outcomes.append(Outcome(s, score, score, score, reps, seconds))
    return outcomes


# ------------------------------------------------------------------ reporting


def _mean(values: list[float]) -> float:
    return float(np.mean(values)) if values else float("nan")


def stage_metrics(outcomes: list[Outcome], stage: str) -> dict[str, float]:
    """Per-sample means of π, α, α* (tn = 0), fp and fn at one stage."""
    cs = [getattr(o, stage) for o in outcomes]
    return {
        "pi": _mean([c.precision for c in cs]),
        "alpha": _mean([c.accuracy for c in cs]),
        "strict": _mean([c.strict_accuracy for c in cs]),
        "fp": _mean([c.fp for c in cs]),
        "fn": _mean([c.fn for c in cs]),
    }


def by_exercise(outcomes: list[Outcome]) -> dict[str, list[Outcome]]:
    groups: dict[str, list[Outcome]] = {}
    for o in outcomes:
        groups.setdefault(o.session.exercise, []).append(o)
    return groups


def exercise_average(outcomes: list[Outcome], stage: str) -> dict[str, float]:
    """Metrics averaged per exercise first, then over exercises (the thesis's "Average" row)."""
    rows = [stage_metrics(v, stage) for v in by_exercise(outcomes).values()]
    return {k: _mean([r[k] for r in rows]) for k in rows[0]}


def _cells(m: dict[str, float]) -> str:
    return f"{m['pi']:.2f} | {m['alpha']:.3f} | {m['strict']:.2f} | {m['fp']:.2f} | {m['fn']:.2f}"


def _reps(outcomes: list[Outcome]) -> float:
    return _mean([float(o.reps == o.session.rep_count) for o in outcomes])


def table_57(outcomes: list[Outcome], dtw: list[Outcome]) -> str:
    """Tables 5.7 + 5.8: per exercise, identification, refining (clustering + selection, then
    our grammar/relocation when configured), after periodic analysis, and the DTW baseline."""
    stages = ("id", "ref", "final", "DTW")
    head = "| exercise | " + " | ".join(
        f"{s} {m}" for s in stages for m in ("π", "α", "α*", "fp", "fn")
    )
    lines = [head + " | reps exact | s/session |", "|---" * 23 + "|"]
    groups, dtw_groups = by_exercise(outcomes), by_exercise(dtw)
    rows = [(ex, groups[ex], dtw_groups[ex]) for ex in sorted(groups)] + [
        ("**mean**", outcomes, dtw)
    ]
    for ex, g, d in rows:
        avg = stage_metrics if ex != "**mean**" else exercise_average
        lines.append(
            f"| {ex} | {_cells(avg(g, 'identified'))} | {_cells(avg(g, 'refined'))} | "
            f"{_cells(avg(g, 'final'))} | "
            f"{_cells(avg(d, 'final'))} | {_reps(g):.2f} | {_mean([o.seconds for o in g]):.3f} |"
        )
    return "\n".join(lines)


SUMMARY_HEAD = (
    "| configuration | protocol | π | α | α* | fp | fn | reps exact | s/session | max s |\n"
    "|---|---|---|---|---|---|---|---|---|---|"
)


def summary_row(name: str, protocol: str, outcomes: list[Outcome]) -> str:
    m = exercise_average(outcomes, "final")
    return (
        f"| {name} | {protocol} | {_cells(m)} | {_reps(outcomes):.2f} "
        f"| {_mean([o.seconds for o in outcomes]):.3f} | {max(o.seconds for o in outcomes):.3f} |"
    )


CLASSIFIERS: tuple[ClassifierName, ...] = ("c45", "nb", "svm")
CLUSTERINGS: tuple[Clustering, ...] = ("em", "kmeans", "tc")
SELECTIONS: tuple[Selection, ...] = ("mu1", "mu2")
GRID_COLUMNS = [(c, ab) for c in CLASSIFIERS for ab in (False, True)]
GRID_ROWS = [(cl, se) for cl in CLUSTERINGS for se in SELECTIONS]


def grid_scores(data: dict[str, list[Session]], subjects: tuple[str, ...]) -> dict[tuple, list]:
    """Refined confusions per (classifier, AdaBoost, clustering, selection): one fit and one
    identification per fold and classifier, then every refining on the same candidates."""
    cells: dict[tuple, list[tuple[str, Confusion]]] = {}
    for clf, ab in GRID_COLUMNS:
        options = replace(FAITHFUL, classifier=clf, adaboost=ab)
        for sessions in data.values():
            for test in subjects:
                tutor, train, tests = split(sessions, test, "loso")
                model = LandmarkModel(options=options)
                model.fit(
                    tutor.motion,
                    tutor.frames,
                    tutor.types,
                    [(s.motion, s.frames, s.types) for s in train],
                )
                for s in tests:
                    found = model.detect(s.motion)
                    for cl, se in GRID_ROWS:
                        opts = replace(FAITHFUL.refine, clustering=cl, selection=se)
                        refined = refine(found.candidates, found.signature, model.means_, opts)
                        cells.setdefault((clf, ab, cl, se), []).append(
                            (s.exercise, _score(s, refined))
                        )
    return cells


def run_grid(data: dict[str, list[Session]], subjects: tuple[str, ...]) -> str:
    """Table 5.5: classifier (± AdaBoost) × clustering × selection on the faithful pipeline;
    refined π / α* per sample averaged per exercise then over exercises (protocol loso)."""
    cells = grid_scores(data, subjects)
    head = "| clust. | sel. | " + " | ".join(
        f"{c}{'+AB' if ab else ''} π / α*" for c, ab in GRID_COLUMNS
    )
    lines = [head + " |", "|---" * (len(GRID_COLUMNS) + 2) + "|"]
    for cl, se in GRID_ROWS:
        row = []
        for clf, ab in GRID_COLUMNS:
            per: dict[str, list[Confusion]] = {}
            for exercise, c in cells[(clf, ab, cl, se)]:
                per.setdefault(exercise, []).append(c)
            pi = _mean([_mean([c.precision for c in v]) for v in per.values()])
            strict = _mean([_mean([c.strict_accuracy for c in v]) for v in per.values()])
            row.append(f"{pi:.2f} / {strict:.2f}")
        lines.append(f"| {cl} | {se} | " + " | ".join(row) + " |")
    return "\n".join(lines)


def ablation_steps() -> list[tuple[str, LandmarkOptions]]:
    """From the faithful configuration to ours, one documented change at a time (cumulative)."""
    ours = LandmarkOptions()
    steps = [("faithful (thesis)", FAITHFUL)]
    changes: list[tuple[str, dict[str, object]]] = [
        (
            "+ mirrored side chosen per performance",
            {"signature": replace(FAITHFUL.signature, mirror=True)},
        ),
        ("+ signature ω = 0.5 s, PCs standardised per performance", {"signature": ours.signature}),
        ("+ recording ends count as extrema", {"ends": True}),
        ("+ clusters split at gaps > β = 15 frames", {"refine": ours.refine}),
        ("+ extreme key poses placed at the farthest pose", {"relocate": True}),
        ("+ grammar typing (retype / insert / delete)", {"grammar": ours.grammar}),
        ("+ 4 augmented tutor copies (cold start only) = ours", {"augment": ours.augment}),
    ]
    for name, change in changes:
        steps.append((name, replace(steps[-1][1], **change)))  # type: ignore[arg-type]
    assert steps[-1][1] == ours
    return steps


def run_ablation(data: dict[str, list[Session]], subjects: tuple[str, ...], protocol: str) -> str:
    lines = [SUMMARY_HEAD]
    for name, options in ablation_steps():
        outcomes = run_config(Config(name, options, protocol, True), data, subjects)
        lines.append(summary_row(name, protocol, outcomes))
    return "\n".join(lines)


def with_overrides(options: LandmarkOptions, settings: list[str]) -> LandmarkOptions:
    """LandmarkOptions with FIELD=VALUE overrides (Python literals); nested fields as
    signature.FIELD, refine.FIELD or grammar.FIELD."""
    for item in settings:
        key, text = item.split("=", 1)
        value: Any
        try:
            value = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            value = text
        if "." in key:
            outer, inner = key.split(".", 1)
            nested: Any = getattr(options, outer) or GrammarOptions()
            changed: dict[str, Any] = {outer: replace(nested, **{inner: value})}
            options = replace(options, **changed)
        elif key == "grammar" and value is None:
            options = replace(options, grammar=None)
        else:
            options = replace(options, **{key: value})
    return options


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=Path("data/ui-prmd"))
    parser.add_argument("--exercises", default=",".join(EXERCISES))
    parser.add_argument("--subjects", default=",".join(SUBJECTS), help="test subjects")
    parser.add_argument("--configs", default="faithful,ours", help=",".join(CONFIGS))
    parser.add_argument("--protocols", default="loso,tutor")
    parser.add_argument("--augment", type=int, default=None, help="tutor copies (protocol tutor)")
    parser.add_argument("--no-periodic", action="store_true", help="skip analysis.periodic.clean")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="FIELD=VALUE",
        help="override a LandmarkOptions field, e.g. refine.beta=12.0",
    )
    parser.add_argument("--grid", action="store_true", help="Table 5.5 grid (slow: EM)")
    parser.add_argument("--quick", action="store_true", help="m01,m07; test subjects s02,s04,s06")
    parser.add_argument("--tables", action="store_true", help="per-exercise tables 5.7/5.8")
    parser.add_argument("--ablation", action="store_true", help="faithful → ours, step by step")
    args = parser.parse_args(argv)
    if args.quick:
        args.exercises, args.subjects = "m01,m07", "s02,s04,s06"
    subjects = tuple(args.subjects.split(","))
    t0 = time.perf_counter()
    data = {ex: load_sessions(args.data, ex) for ex in args.exercises.split(",")}
    print(f"# eval_landmarks — {time.strftime('%Y-%m-%d')} — {platform.node()}")
    n_sessions = sum(len(v) for v in data.values())
    print(f"{n_sessions} sessions loaded in {time.perf_counter() - t0:.1f} s\n")
    dtw = run_dtw(data, subjects)
    print(SUMMARY_HEAD)
    print(summary_row("DTW baseline (tutor landmarks over the DTW path)", "tutor", dtw))
    results = {}
    for name in args.configs.split(","):
        for protocol in args.protocols.split(","):
            options = with_overrides(CONFIGS[name].options, args.set)
            if args.augment is not None:
                options = replace(options, augment=args.augment)
            config = Config(CONFIGS[name].name, options, protocol, not args.no_periodic)
            results[(name, protocol)] = run_config(config, data, subjects)
            print(summary_row(config.name, protocol, results[(name, protocol)]), flush=True)
    if args.tables or not args.quick:
        for (name, protocol), outcomes in results.items():
            print(f"\n### Tables 5.7/5.8 — {CONFIGS[name].name}, protocol {protocol}\n")
            print(table_57(outcomes, dtw))
    if args.ablation:
        for protocol in args.protocols.split(","):
            print(f"\n### Ablation, protocol {protocol} (after periodic analysis)\n")
            print(run_ablation(data, subjects, protocol))
    if args.grid:
        print("\n### Table 5.5 — refined π / α* per sample (faithful pipeline, protocol loso)\n")
        print(run_grid(data, subjects))
    print(f"\ntotal {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
