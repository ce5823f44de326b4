"""Paper 001's guidance on UI-PRMD sessions with a known mistake.

Every correct session of the development subjects (s02–s07) is analysed as recorded and with one
mistake made on purpose (tests/analysis/guidance_cases.py): re-timed ×0.6 ("too fast") and ×1.6
("too slow"), every joint's movement scaled ×0.6 ("incomplete") and ×1.3 ("overdone"). Reports,
per mistake, the share of repetitions whose first guidance is the matching type, and the share of
repetitions of the unmodified sessions that get no guidance. Two ways of knowing the patient's
own pace (`analysis.pipeline.gestures.pace_guidance`):

- first session: none from before, so each repetition is judged against the tutor's and against
  the session's repetitions so far (a whole session done quicker is this patient's pace);
- earlier session known: the patient's usual tempo and reach from the unmodified take
  (`repetition_stage.session_pace`, what a previous session of the same exercise gives) are
  passed as ``own_pace``; the unmodified take is then judged against itself, so its column is
  in-sample (UI-PRMD has one correct take per subject and exercise).

Models: cold start (s01's correct session alone) or trained (leave one subject out).

    python -m bench.eval_guidance [--exercises m01,m02] [--jobs 2] [--trained]
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from analysis.bvh import Motion
from analysis.pipeline import analyse, build_model
from analysis.pipeline.gestures import Pace
from analysis.pipeline.model import FittedModel
from analysis.pipeline.prepare import prepare
from analysis.pipeline.repetition_stage import session_pace
from bench.eval_assessment import SUBJECTS, load_sessions, training_items
from bench.eval_live import machine
from tests.analysis.guidance_cases import EXPECTED, modified

MODES = ("first session", "earlier session known")


def earlier_pace(motion: Motion, model: FittedModel, spans: list[tuple[int, int]]) -> Pace | None:
    parts = model.components
    prepared = prepare(motion, model.tutor.skeleton, model.fps, parts.axis.rep_frames)
    return session_pace(prepared, spans, model)


def count(
    motion: Motion,
    model: FittedModel,
    expected: str,
    own: Pace | None,
    tally: tuple[Counter, Counter],
) -> None:
    hits, totals = tally
    for rep in analyse(motion, model, own_pace=own).summary.repetitions:
        totals[expected] += 1
        hits[expected] += rep.main_guidance == ("" if expected == "none" else expected)


def evaluate(args: tuple[Path, str, bool]) -> dict[str, tuple[Counter, Counter]]:
    """One exercise: {mode: (hits, totals)} (a worker process with ``--jobs``)."""
    data, exercise, trained = args
    tutor, sessions = load_sessions(data, exercise)
    cold = build_model(tutor.motion, tutor.landmark_frames, tutor.landmark_types)
    out: dict[str, tuple[Counter, Counter]] = {mode: (Counter(), Counter()) for mode in MODES}
    for subject in SUBJECTS:
        model = cold
        if trained:
            model = build_model(
                tutor.motion, tutor.landmark_frames, tutor.landmark_types,
                training=training_items(sessions, subject),
            )  # fmt: skip
        for session in (s for s in sessions if s.subject == subject and s.correct):
            reps = analyse(session.motion, model).summary.repetitions
            own = earlier_pace(session.motion, model, [(r.start, r.end) for r in reps])
            for mode, pace in zip(MODES, (None, own), strict=True):
                count(session.motion, model, "none", pace, out[mode])
                for (kind, factor), expected in EXPECTED.items():
                    changed = modified(session.motion, kind, factor)
                    count(changed, model, expected, pace, out[mode])
    print(f"{exercise} done", flush=True)
    return out


def table(results: dict[str, dict[str, tuple[Counter, Counter]]], mode: str) -> str:
    kinds = [*EXPECTED.values(), "none"]
    head = " | ".join(k if k != "none" else "unmodified: no guidance" for k in kinds)
    lines = [f"| exercise | {head} |", "|---" * (len(kinds) + 1) + "|"]
    all_hits: Counter = Counter()
    all_totals: Counter = Counter()
    for exercise, by_mode in results.items():
        hits, totals = by_mode[mode]
        all_hits += hits
        all_totals += totals
        cells = " | ".join(f"{hits[k] / max(totals[k], 1):.2f}" for k in kinds)
        lines.append(f"| {exercise} | {cells} |")
    cells = " | ".join(f"**{all_hits[k] / max(all_totals[k], 1):.2f}**" for k in kinds)
    lines.append(f"| **all** | {cells} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=Path("data/ui-prmd"))
    parser.add_argument("--exercises", default=",".join(f"m{k:02d}" for k in range(1, 11)))
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--trained", action="store_true", help="leave-one-subject-out models")
    args = parser.parse_args()
    exercises = args.exercises.split(",")
    started = time.perf_counter()
    jobs = [(args.data, e, args.trained) for e in exercises]
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        results = dict(zip(exercises, pool.map(evaluate, jobs), strict=True))
    models = "trained (leave one subject out)" if args.trained else "cold start (tutor only)"
    print(
        f"\nUI-PRMD guidance evaluation, {time.strftime('%Y-%m-%d')}, {models}, on {machine()} "
        f"(Python {platform.python_version()}, load {os.getloadavg()[0]:.1f}), "
        f"{time.perf_counter() - started:.0f} s"
    )
    for mode in MODES:
        print(f"\n#### {mode}\n\n{table(results, mode)}")


if __name__ == "__main__":
    main()
