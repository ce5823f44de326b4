"""Paper 001's guidance on UI-PRMD sessions with a known mistake.

Every correct session of the development subjects (s02–s07) is analysed as recorded and with one
mistake made on purpose (tests/analysis/guidance_cases.py): re-timed ×0.6 ("too fast") and ×1.6
("too slow"), every joint's movement scaled ×0.6 ("incomplete") and ×1.3 ("overdone"). Reports,
per mistake, the share of repetitions whose first guidance is the matching type, and the share of
repetitions of the unmodified sessions that get no guidance. Models: cold start (s01's correct
session alone) and trained (leave one subject out: the other subjects' labelled sessions).

    python -m bench.eval_guidance [--exercises m01,m02] [--no-trained]
"""

from __future__ import annotations

import argparse
import time
from collections import Counter
from pathlib import Path

from analysis.pipeline import analyse, build_model
from bench.eval_assessment import SUBJECTS, load_sessions, training_items
from tests.analysis.guidance_cases import EXPECTED, modified


def evaluate(data: Path, exercise: str, trained: bool, hits: Counter, totals: Counter) -> None:
    tutor, sessions = load_sessions(data, exercise)
    cold = build_model(tutor.motion, tutor.landmark_frames, tutor.landmark_types)
    for subject in SUBJECTS:
        model = cold
        if trained:
            model = build_model(
                tutor.motion, tutor.landmark_frames, tutor.landmark_types,
                training=training_items(sessions, subject),
            )  # fmt: skip
        for session in (s for s in sessions if s.subject == subject and s.correct):
            for rep in analyse(session.motion, model).summary.repetitions:
                totals["none"] += 1
                hits["none"] += not rep.guidance
            for (kind, factor), expected in EXPECTED.items():
                changed = modified(session.motion, kind, factor)
                for rep in analyse(changed, model).summary.repetitions:
                    totals[expected] += 1
                    hits[expected] += rep.main_guidance == expected


def table(data: Path, exercises: list[str], trained: bool) -> None:
    title = "trained (leave one subject out)" if trained else "cold start (tutor only)"
    kinds = [*EXPECTED.values(), "none"]
    print(f"\n### {title}\n")
    print("| exercise | " + " | ".join(k if k != "none" else "unmodified: no guidance"
                                       for k in kinds) + " |")  # fmt: skip
    print("|---" * (len(kinds) + 1) + "|")
    all_hits: Counter = Counter()
    all_totals: Counter = Counter()
    for exercise in exercises:
        hits: Counter = Counter()
        totals: Counter = Counter()
        evaluate(data, exercise, trained, hits, totals)
        all_hits += hits
        all_totals += totals
        cells = " | ".join(f"{hits[k] / max(totals[k], 1):.2f}" for k in kinds)
        print(f"| {exercise} | {cells} |", flush=True)
    cells = " | ".join(f"**{all_hits[k] / max(all_totals[k], 1):.2f}**" for k in kinds)
    print(f"| **all** | {cells} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=Path("data/ui-prmd"))
    parser.add_argument("--exercises", default=",".join(f"m{k:02d}" for k in range(1, 11)))
    parser.add_argument("--no-trained", action="store_true")
    parser.add_argument("--no-cold", action="store_true")
    args = parser.parse_args()
    exercises = args.exercises.split(",")
    print(f"UI-PRMD guidance evaluation, {time.strftime('%Y-%m-%d')}")
    if not args.no_cold:
        table(args.data, exercises, trained=False)
    if not args.no_trained:
        table(args.data, exercises, trained=True)


if __name__ == "__main__":
    main()
