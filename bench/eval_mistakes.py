"""Corrections on UI-PRMD sessions with a mistake made on purpose (issue 26).

Every correct session of the development subjects (s02–s07) is analysed, cold start (the model is
built from s01's correct session alone, so every tested subject is one it never saw), as recorded
and with one mistake made by editing its rotation channels:

- ``reach``: every joint's rotation away from the session's first pose scaled ×0.55, so the
  involved joints reach 55 % of their excursion (right: "bend", "raise", or "turn" for the
  shoulder's rotation); the truth of the amount is the loss in the
  patient's own excursion: the clinical angle's median range over the unmodified session's
  repetitions minus the modified one's.
- ``arm down``: the arm that does the exercise (collar, upper arm, forearm, hand; the side whose
  shoulder flexion, abduction or elevation ranges further in the session, `moving_arm`) kept in
  its first-frame pose (arm exercises only); right: "raise" that arm, or "turn" it in m09
  (shoulder rotation, whose arm is already raised: left still, it did not turn).
- ``lean``: the trunk (the spine's rotation, about the pelvis's left-right axis) leaned 20°
  forward in every frame; the truth is the change of the median trunk flexion. (These two are
  made by `tests/analysis/mistake_cases.py`.)
- ``too fast`` / ``too slow``: the take re-timed ×0.6 / ×1.6 (`tests/analysis/guidance_cases.py`).

Every mistake is analysed as the worker analyses a later session of the same patient and
exercise: with the patient's usual pace from the unmodified session as ``own_pace``
(`analysis.pipeline.repetition_stage.session_pace`). The tempo mistakes are also analysed as a
first session (no earlier pace: judged against the tutor's alone), in their own columns.

Per kind: the share of sessions whose first correction names the right body part and direction,
the share whose amount is within 40 % of the truth (reach, lean), the share that fail; for the
unmodified sessions, the share with no correction of `LARGE_DEG` or more and the share passing.

    .venv/bin/python -m bench.eval_mistakes [--exercises m01,m07] [--jobs 2]
        [--markdown docs/sections/eval_mistakes.md]
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from analysis.bvh import Motion
from analysis.clinical import angle_series
from analysis.pipeline import AnalysisSummary, FittedModel, analyse, build_model
from analysis.pipeline.gestures import Pace
from analysis.pipeline.prepare import prepare
from analysis.pipeline.repetition_stage import session_pace
from bench.eval_assessment import SUBJECTS, load_sessions
from tests.analysis.guidance_cases import range_scaled, retimed
from tests.analysis.mistake_cases import arm_down, forward_lean

DATA = Path("data/ui-prmd")
LARGE_DEG = 10.0  # a correction this large or larger is not a small tip
REACH, CLOSE = 0.55, 0.4
KINDS = ("reach", "arm down", "lean", "too fast", "too slow")
LEGS = {"knee", "hip", "leg", "knees", "hips", "legs"}
ARMS = {"arm", "arms", "elbow", "elbows"}
# per exercise: the body parts its reach lies in (the word after the side), and the moving arm
EXERCISES: dict[str, tuple[set[str], str]] = {
    "m01": (LEGS, ""), "m02": (LEGS, ""), "m03": (LEGS, ""), "m04": (LEGS, ""),
    "m05": (LEGS, ""), "m06": (LEGS, ""), "m07": (ARMS, "Right"), "m08": (ARMS, "Right"),
    "m09": (ARMS, "Right"), "m10": (ARMS, "Right"),
}  # fmt: skip
ARM_RANGES = ("shoulder_flexion", "shoulder_abduction", "shoulder_elevation")
# an arm left still is told to do the exercise's own movement: raised, or turned in m09
ARM_DOWN_DIRECTIONS = {"m09": {"turn"}}
EXPECTED_DIRECTIONS = {
    "reach": {"bend", "raise", "turn"}, "arm down": {"raise"}, "lean": {"straighten"},
    "too fast": {"slow down"}, "too slow": {"speed up"},
}  # fmt: skip


def median_ranges(summary: AnalysisSummary) -> dict[str, float]:
    names = {n for r in summary.repetitions for n in r.clinical_angles}
    return {n: float(np.median([r.clinical_angles[n].range for r in summary.repetitions
                                if n in r.clinical_angles])) for n in names}  # fmt: skip


def first_correction(summary: AnalysisSummary) -> Any:
    corrections = summary.advice.corrections
    return corrections[0] if corrections else None


def right_words(kind: str, correction: Any, exercise: str, side: str = "") -> bool:
    """Whether a correction names the body part and direction the mistake calls for."""
    expected = EXPECTED_DIRECTIONS[kind]
    if kind == "arm down":
        expected = ARM_DOWN_DIRECTIONS.get(exercise, expected)
    if correction is None or correction.direction not in expected:
        return False
    words = correction.part.split()
    parts, parts_side = EXERCISES[exercise]
    if kind == "reach":
        return words[-1] in parts
    if kind == "arm down":
        return words[-1] == "arm" and words[0] == (side or parts_side).lower()
    return kind != "lean" or words[-1] == "trunk"


def truth(kind: str, correction: Any, own: dict[str, float], changed: AnalysisSummary,
          lean: float) -> float | None:  # fmt: skip
    """The amount the mistake took away (module docstring); None where no amount is asked."""
    if kind == "lean":
        return lean
    if kind != "reach" or correction is None or correction.angle not in own:
        return None
    return own[correction.angle] - median_ranges(changed).get(correction.angle, np.nan)


@cache
def cold_model(data: Path, exercise: str) -> FittedModel:
    tutor, _ = load_sessions(data, exercise)
    return build_model(tutor.motion, tutor.landmark_frames, tutor.landmark_types)


def moving_arm(motion: Motion) -> str:
    """ "Left" or "Right": the arm that does the exercise, the one whose shoulder angle (flexion,
    abduction or elevation: `analysis.clinical`) ranges further over the session. (The upper
    arm's local rotation picked m08's left arm, whose twist about its own axis is large while
    the right arm does the shoulder extension.)"""
    series = angle_series(motion)
    reach = {side: max((float(np.nanpercentile(series[n], 95) - np.nanpercentile(series[n], 5))
                        for n in series if n.startswith(ARM_RANGES) and n.endswith(side.lower())),
                       default=0.0)
             for side in ("Left", "Right")}  # fmt: skip
    return max(reach, key=lambda side: reach[side])


def mistakes(motion: Motion, exercise: str) -> dict[str, tuple[Motion, float]]:
    made = {
        "reach": (range_scaled(motion, REACH), 0.0), "lean": forward_lean(motion),
        "too fast": (retimed(motion, 0.6), 0.0), "too slow": (retimed(motion, 1.6), 0.0),
    }  # fmt: skip
    if EXERCISES[exercise][1]:
        made["arm down"] = (arm_down(motion, moving_arm(motion)), 0.0)
    return made


def evaluate(data: Path, exercise: str, subject: str) -> Counter:
    """One correct session and its mistakes: counts of sessions, hits and close amounts."""
    model = cold_model(data, exercise)
    _, sessions = load_sessions(data, exercise)
    session = next(s for s in sessions if s.subject == subject and s.correct)
    plain = analyse(session.motion, model).summary
    counts: Counter = Counter(
        {"unmodified": 1, "unmodified quiet": all(c.amount < LARGE_DEG or c.unit != "°"
                                                  for c in plain.advice.corrections),
         "unmodified passes": (plain.score or 0.0) >= plain.pass_threshold}
    )  # fmt: skip
    own = median_ranges(plain)
    pace = usual_pace_of(session.motion, model, plain)
    side = moving_arm(session.motion) if EXERCISES[exercise][1] else ""
    for kind, (motion, lean) in mistakes(session.motion, exercise).items():
        summary = analyse(motion, model, own_pace=pace).summary
        first = first_correction(summary)
        if kind in ("too fast", "too slow"):
            alone = first_correction(analyse(motion, model).summary)
            counts[f"{kind} right alone"] += right_words(kind, alone, exercise, side)
        counts[kind] += 1
        counts[f"{kind} fails"] += (summary.score or 0.0) < summary.pass_threshold
        counts[f"{kind} right"] += right_words(kind, first, exercise, side)
        true = truth(kind, first, own, summary, lean)
        if kind in ("reach", "lean"):
            close = (
                first is not None
                and true is not None
                and true > 0
                and abs(first.amount - true) <= CLOSE * true
            )
            counts[f"{kind} close"] += bool(close and right_words(kind, first, exercise, side))
        if first is not None and os.environ.get("EVAL_MISTAKES_VERBOSE"):
            print(exercise, subject, kind, first.text, f"truth {true}", flush=True)
    return counts


def usual_pace_of(motion: Motion, model: FittedModel, summary: AnalysisSummary) -> Pace | None:
    """The patient's usual pace in the unmodified session, as an earlier session gives it."""
    parts = model.components
    prepared = prepare(motion, model.tutor.skeleton, model.fps, parts.axis.rep_frames)
    return session_pace(prepared, [(r.start, r.end) for r in summary.repetitions], model)


def _share(counts: Counter, key: str, total: str) -> str:
    return f"{counts[key] / counts[total]:.2f}" if counts[total] else "–"


HEADER = ("| exercise | reach: right | reach: amount | reach: fails | arm down: right | "
          "lean: right | lean: amount | too fast: right | too slow: right | "
          "too fast, first session: right | too slow, first session: right | "
          "unmodified: no correction ≥ 10° | unmodified: pass |")  # fmt: skip


def row(name: str, c: Counter) -> str:
    cells = [
        _share(c, "reach right", "reach"), _share(c, "reach close", "reach"),
        _share(c, "reach fails", "reach"), _share(c, "arm down right", "arm down"),
        _share(c, "lean right", "lean"), _share(c, "lean close", "lean"),
        _share(c, "too fast right", "too fast"), _share(c, "too slow right", "too slow"),
        _share(c, "too fast right alone", "too fast"),
        _share(c, "too slow right alone", "too slow"),
        _share(c, "unmodified quiet", "unmodified"), _share(c, "unmodified passes", "unmodified"),
    ]  # fmt: skip
    return f"| {name} | " + " | ".join(cells) + " |"


def run(data: Path, exercises: list[str], jobs: int) -> list[str]:
    tasks = [(data, e, s) for e in exercises for s in SUBJECTS]
    with ProcessPoolExecutor(max_workers=max(1, jobs)) as pool:
        results = list(pool.map(evaluate, *zip(*tasks, strict=True)))
    lines = [HEADER, "|---" * 13 + "|"]
    total: Counter = Counter()
    for exercise in exercises:
        counts = sum((r for (_, e, _), r in zip(tasks, results, strict=True) if e == exercise),
                     Counter())  # fmt: skip
        total += counts
        lines.append(row(exercise, counts))
    lines.append(row("**all**", total))
    sessions = total["unmodified"]
    lines.append(f"\n{sessions} correct sessions ({len(exercises)} exercises × subjects "
                 f"{SUBJECTS[0]}–{SUBJECTS[-1]}), each with {len(KINDS)} kinds of mistake "
                 "(arm down: arm exercises only).")  # fmt: skip
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--exercises", default=",".join(EXERCISES))
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--markdown", type=Path, help="write the table into this section file")
    args = parser.parse_args()
    started = time.perf_counter()
    lines = run(args.data, args.exercises.split(","), args.jobs)
    stamp = (f"Measured {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} on "
             f"{platform.machine()} ({os.cpu_count()} cores, Python {platform.python_version()}), "
             f"{time.perf_counter() - started:.0f} s with --jobs {args.jobs}.")  # fmt: skip
    print("\n".join(lines) + "\n\n" + stamp)
    if args.markdown:
        write_section(args.markdown, lines, stamp)


def write_section(path: Path, lines: list[str], stamp: str) -> None:
    """Replace the generated table between the section's markers (or append it)."""
    begin, end = "<!-- eval_mistakes table -->", "<!-- end of eval_mistakes table -->"
    text = path.read_text() if path.exists() else "## Corrections on mistakes made on purpose\n"
    table = "\n".join([begin, "", stamp, "", *lines, "", end])
    if begin in text and end in text:
        text = text[: text.index(begin)] + table + text[text.index(end) + len(end) :]
    else:
        text = text.rstrip() + "\n\n" + table + "\n"
    path.write_text(text)


if __name__ == "__main__":
    main()
