"""How far apart correct and re-timed / re-scaled takes are on candidate tempo and reach measures
(issue 34: can any band against the reference name a ×0.6 / ×1.6 take in a first session?).

For every correct development session of UI-PRMD (s02–s07) as recorded and with the mistakes of
`tests/analysis/guidance_cases.py`, the pipeline's own repetitions (`find_repetitions`, cold-start
model), and per repetition: its duration over the tutor's (what `pace_guidance` judges), the span
of its moving part (involved joints' angular speed above a share of its peak), path length over
speed, the slope of its warping path against the tutor's repetition, and its reach (the
`repetition_pace` excursion, and the per-joint median of ratios). Prints, per measure, the 10th /
50th / 90th percentiles of the unmodified and modified repetitions and the best single band (the
one whose worst share of "mistake named" and "unmodified left alone" is largest).

    python -m bench.guidance_measures [--exercises m01,m02] [--jobs 2]
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import numpy.typing as npt

from analysis.bvh.plausibility import DEFAULT_LIMITS
from analysis.kinematics import quaternions as quat
from analysis.pipeline import build_model
from analysis.pipeline.gestures import align_gesture, excursion
from analysis.pipeline.repetition_stage import pace_reference
from analysis.pipeline.run import StageTimer, find_repetitions
from bench.eval_assessment import load_sessions
from tests.analysis.guidance_cases import EXPECTED, modified

FloatArray = npt.NDArray[np.float64]
Row = dict[str, float | str]
MOVING = 0.1  # share of the peak speed above which a frame is part of the moving span


def raw(q: FloatArray, mirror_q: FloatArray, weights: FloatArray) -> dict[str, float]:
    """Per repetition, before dividing by the tutor's: span, path length, speeds, extreme."""
    moved = excursion(q) + excursion(mirror_q)
    q, mirror_q = quat.make_continuous(q, axis=0), quat.make_continuous(mirror_q, axis=0)
    steps = quat.angle_between(q[:-1], q[1:], degrees=True)
    steps = steps + quat.angle_between(mirror_q[:-1], mirror_q[1:], degrees=True)
    speed = np.asarray(steps, dtype=np.float64) @ weights if len(q) > 1 else np.zeros(1)
    smooth = np.convolve(speed, np.ones(3) / 3, mode="same") if speed.size >= 3 else speed
    peak = max(float(smooth.max()), 1e-9)
    active = np.flatnonzero(smooth > MOVING * peak)
    return {
        "span": float(active[-1] - active[0] + 1) if active.size else 1.0,
        "path": float(speed.sum()),
        "p90": max(float(np.percentile(smooth, 90)), 1e-9),
        "extreme": float(np.argmax(moved @ weights)),
        **{f"joint{j}": float(v) for j, v in enumerate(moved.max(axis=0))},
        "reach_w": float((moved @ weights).max()),
    }


def exercise_rows(args: tuple[Path, str]) -> list[Row]:
    data, exercise = args
    tutor, sessions = load_sessions(data, exercise)
    model = build_model(tutor.motion, tutor.landmark_frames, tutor.landmark_types)
    parts = model.components
    step, reps = parts.scoring_step, parts.tutor_reps
    index, mirror, reference, tutor_frames = pace_reference(model)
    weights = reference / max(float(reference.sum()), 1e-9)
    found = find_repetitions(tutor.motion, model, DEFAULT_LIMITS, None, StageTimer(None))
    tq = found.prepared.local_q
    tutor_raw = [raw(tq[a : b + 1 : step][:, index], tq[a : b + 1 : step][:, mirror], weights)
                 for a, b in reps]  # fmt: skip
    typical = {k: float(np.median([t[k] for t in tutor_raw])) for k in tutor_raw[0]}
    cases = [("none", 1.0, "none"), *((k, f, e) for (k, f), e in EXPECTED.items())]
    rows: list[Row] = []
    for session in (s for s in sessions if s.correct):
        for kind, factor, label in cases:
            motion = session.motion if kind == "none" else modified(session.motion, kind, factor)
            cut = find_repetitions(motion, model, DEFAULT_LIMITS, None, StageTimer(None))
            local_q, segments = cut.prepared.local_q, cut.cut.segments
            for k, (a, b) in enumerate(zip(segments.starts, segments.ends, strict=True)):
                patient = local_q[int(a) : int(b) + 1 : step]
                own = raw(patient[:, index], patient[:, mirror], weights)
                ta, tb = reps[k % len(reps)]
                path = align_gesture(parts.papers.tutor_q[ta : tb + 1 : step], patient[:, index],
                                     parts.papers.joint_weights).path  # fmt: skip
                m = int(path[:, 0].max()) + 1
                lo, hi = int(0.1 * m), int(0.9 * m)
                slope = (path[path[:, 0] <= hi][-1, 1] - path[path[:, 0] >= lo][0, 1]) / max(
                    hi - lo, 1
                )
                speed_ratio = own["p90"] / typical["p90"]
                big = reference > 0.2 * reference.max()
                per_joint = [own[f"joint{j}"] / reference[j] for j in np.flatnonzero(big)]
                rows.append({
                    "exercise": exercise, "subject": session.subject, "label": label,
                    "duration": (int(b) - int(a) + 1) / tutor_frames,
                    "moving span": own["span"] / typical["span"],
                    "path over speed": own["path"] / typical["path"] / speed_ratio,
                    "time to extreme pose": own["extreme"] / max(typical["extreme"], 1.0),
                    "warping path slope": max(float(slope), 0.0) * (tb - ta + 1) / tutor_frames,
                    "reach": own["reach_w"] / max(float(weights @ reference), 1e-9),
                    "reach per joint": float(np.median(per_joint)),
                })  # fmt: skip
    print(f"{exercise} done", flush=True)
    return rows


TAKE_TEMPO = ("duration, take's median", "duration, take's median over other subjects'")
TAKE_REACH = ("reach, take's median", "reach, take's median over other subjects'")


def add_take_measures(rows: list[Row]) -> None:
    """Every repetition given its take's median duration and reach, and those over the median
    of the other subjects' unmodified repetitions of the exercise (what a model trained on
    them could know): the spread left when a take is judged as a whole."""
    takes: dict[tuple[str, str, str], list[Row]] = {}
    for row in rows:
        takes.setdefault((str(row["exercise"]), str(row["subject"]), str(row["label"])), []).append(
            row
        )
    for (exercise, subject, _), members in takes.items():
        for key, names in (("duration", TAKE_TEMPO), ("reach", TAKE_REACH)):
            median = float(np.median([float(r[key]) for r in members]))
            others = [float(r[key]) for r in rows if r["exercise"] == exercise
                      and r["subject"] != subject and r["label"] == "none"]  # fmt: skip
            for row in members:
                row[names[0]] = median
                row[names[1]] = median / max(float(np.median(others)), 1e-9)


def best_band(
    unmodified: FloatArray, low: FloatArray, high: FloatArray
) -> tuple[float, float, float]:
    """(worst share, lower bound, upper bound) of the band that names most of both mistakes
    while leaving most unmodified repetitions alone."""
    best = (0.0, 0.0, 0.0)
    for lo in np.arange(0.3, 1.0, 0.01):
        for hi in np.arange(0.95, 2.2, 0.01):
            named = min(float(np.mean(low < lo)), float(np.mean(high > hi)))
            worst = min(named, float(np.mean((unmodified >= lo) & (unmodified <= hi))))
            if worst > best[0]:
                best = (worst, float(lo), float(hi))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=Path("data/ui-prmd"))
    parser.add_argument("--exercises", default=",".join(f"m{k:02d}" for k in range(1, 11)))
    parser.add_argument("--jobs", type=int, default=1)
    args = parser.parse_args()
    jobs = [(args.data, e) for e in args.exercises.split(",")]
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        rows = [row for rows in pool.map(exercise_rows, jobs) for row in rows]
    add_take_measures(rows)
    print("\n| measure | unmodified | low mistake | high mistake | best band (worst share) |")
    print("|---|---|---|---|---|")
    tempo = ("duration", "moving span", "path over speed", "time to extreme pose",
             "warping path slope")  # fmt: skip
    for measure in (*tempo, *TAKE_TEMPO, "reach", "reach per joint", *TAKE_REACH):
        low, high = (
            ("too fast", "too slow")
            if measure in tempo or measure in TAKE_TEMPO
            else ("incomplete", "overdone")
        )
        values = {
            label: np.array([float(r[measure]) for r in rows if r["label"] == label])
            for label in ("none", low, high)
        }
        spread = [" / ".join(f"{v:.2f}" for v in np.percentile(values[k], [10, 50, 90]))
                  for k in ("none", low, high)]  # fmt: skip
        worst, lo, hi = best_band(values["none"], values[low], values[high])
        print(f"| {measure} | {' | '.join(spread)} | {lo:.2f} / {hi:.2f} ({worst:.2f}) |")


if __name__ == "__main__":
    main()
