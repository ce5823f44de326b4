"""One answer per take, whatever recorded it (issue 35): UI-PRMD recorded every repetition with its
Kinect (data/ui-prmd/sessions, BVH) and with Vicon at once (data/ui-prmd/vicon, Plug-in Gait
``.trc``, subjects s01 and s02). Each paired take is analysed from both recorders against the same
exercise, made once from a Kinect session (s03's correct take, a subject not in the pairs) and
once from a Vicon one (s01's correct take; the pairs it was made from are left out). Per pair:
the same repetition count, scores within 5 points, the same pass/fail (the take's score against
its pass threshold).

    python -m bench.eval_recorders [--jobs 1] [--exercises m01,m04] [--subjects s01]
        [--models kinect,vicon]
    python -m bench.eval_recorders --keraal     # the KERAAL samples' counts and angles, and
                                                # the Kinect's with its lost shoulders kept in

Candidate scoring features are tried on these pairs in minutes with
`bench/eval_recorder_candidates.py`.
"""

from __future__ import annotations

import argparse
import csv
import gzip
import multiprocessing
import platform
import statistics
import time
from dataclasses import dataclass
from pathlib import Path

from analysis.bvh import Motion, read
from analysis.landmarks import suggest_key_poses
from analysis.pipeline import FittedModel, analyse, build_model
from analysis.sources import read_recording

DATA = Path(__file__).resolve().parents[1] / "data" / "ui-prmd"
EXERCISES = [f"m{k:02d}" for k in range(1, 11)]
SCORE_POINTS = 5.0
TARGETS = {"same count": 95.0, "score within 5": 90.0, "same pass/fail": 95.0}


@dataclass(frozen=True)
class Pair:
    model: str  # "kinect" or "vicon": what the exercise was made from
    take: str
    counts: tuple[int, int]  # Kinect, Vicon
    scores: tuple[float, float]
    passed: tuple[bool, bool]


def vicon_motion(name: str) -> Motion:
    content = gzip.decompress((DATA / "vicon" / name).read_bytes())
    return read_recording(name.removesuffix(".gz"), content).motion


def marks() -> dict[str, tuple[list[int], list[int]]]:
    with open(DATA / "landmarks.csv") as handle:
        return {
            r["file"]: ([int(v) for v in r["frames"].split(";")],
                        [int(v) for v in r["types"].split(";")])
            for r in csv.DictReader(handle)
        }  # fmt: skip


def vicon_rows() -> dict[str, dict[str, str]]:
    with open(DATA / "vicon" / "labels.csv") as handle:
        return {r["file"].removesuffix(".trc.gz"): r for r in csv.DictReader(handle)}


def kinect_model(exercise: str) -> FittedModel:
    name = f"sessions/{exercise}_s03_correct.bvh.gz"
    frames, types = marks()[name]
    return build_model(read(DATA / name), frames, types)


def vicon_model(exercise: str) -> FittedModel:
    """The Vicon take of s01's correct session with `vicon_key_poses`."""
    return build_model(*vicon_key_poses(exercise))


def vicon_key_poses(exercise: str) -> tuple[Motion, list[int], list[int]]:
    """The Vicon take of s01's correct session and its key poses, the Kinect session's carried
    over: each repetition's starts from the Vicon labels, the other key poses at the same share
    of the repetition as in the Kinect take."""
    take = f"{exercise}_s01_correct"
    row = vicon_rows()[take]
    frames, types = marks()[f"sessions/{take}.bvh.gz"]
    starts_k = [f for f, t in zip(frames, types, strict=True) if t == 1]
    starts_v = [int(v) for v in row["rep_start_frames"].split(";")]
    motion = vicon_motion(row["file"])
    starts_v.append(motion.n_frames - 1)
    mapped = []
    for frame in frames:
        k = max(i for i, s in enumerate(starts_k) if s <= frame)
        k = min(k, len(starts_v) - 2)
        span_k = max(starts_k[k + 1] - starts_k[k], 1) if k + 1 < len(starts_k) else 1
        share = (frame - starts_k[k]) / span_k
        mapped.append(round(starts_v[k] + share * (starts_v[k + 1] - starts_v[k])))
    mapped = [min(max(f, 0), motion.n_frames - 1) for f in mapped]
    return motion, mapped, types


def judged(motion: Motion, model: FittedModel) -> tuple[int, float, bool]:
    summary = analyse(motion, model).summary
    score = float(summary.score or 0.0)
    return summary.repetition_count, score, score >= summary.pass_threshold


def run_exercise(job: tuple[str, tuple[str, ...], tuple[str, ...]]) -> list[Pair]:
    exercise, subjects, made_from = job
    rows = vicon_rows()
    makers = {"kinect": kinect_model, "vicon": vicon_model}
    models = {m: makers[m](exercise) for m in made_from}
    out = []
    for take, row in sorted(rows.items()):
        if row["exercise"] != exercise or row["subject"] not in subjects:
            continue
        kinect = read(DATA / row["kinect_session"])
        vicon = vicon_motion(row["file"])
        for maker, model in models.items():
            if maker == "vicon" and take == f"{exercise}_s01_correct":
                continue  # the take the exercise was made from
            a, b = judged(kinect, model), judged(vicon, model)
            out.append(Pair(maker, take, (a[0], b[0]), (a[1], b[1]), (a[2], b[2])))
    return out


def shares(pairs: list[Pair]) -> dict[str, float]:
    n = max(len(pairs), 1)
    return {
        "same count": 100.0 * sum(p.counts[0] == p.counts[1] for p in pairs) / n,
        "score within 5": 100.0
        * sum(abs(p.scores[0] - p.scores[1]) <= SCORE_POINTS for p in pairs)
        / n,
        "same pass/fail": 100.0 * sum(p.passed[0] == p.passed[1] for p in pairs) / n,
    }


def table(pairs: list[Pair]) -> str:
    lines = [
        "| exercise made from | pairs | same count | score within 5 | same pass/fail | "
        "median score difference |",
        "|---|---|---|---|---|---|",
    ]
    for made_from in ("kinect", "vicon", "both"):
        chosen = [p for p in pairs if made_from in ("both", p.model)]
        if not chosen:
            continue
        got = shares(chosen)
        diff = statistics.median(abs(p.scores[0] - p.scores[1]) for p in chosen) if chosen else 0
        lines.append(
            f"| {made_from} | {len(chosen)} | {got['same count']:.0f} % | "
            f"{got['score within 5']:.0f} % | {got['same pass/fail']:.0f} % | {diff:.1f} |"
        )
    targets = ", ".join(f"{k} ≥ {v:.0f} %" for k, v in TARGETS.items())
    return "\n".join(lines) + f"\n\nTargets: {targets}."


KERAAL = Path(__file__).resolve().parents[1] / "tests" / "analysis" / "fixtures" / "keraal"
KERAAL_ANGLES = ("shoulder_elevation_left", "shoulder_elevation_right", "trunk_lateral_flexion")


def kept_in(motion: Motion, model: FittedModel) -> str:
    """The shoulder elevation ranges with the lost shoulders' frames kept in (as before the
    import marked them)."""
    angles = analyse(motion, model).summary.clinical_angles
    spans = [angles.get(f"shoulder_elevation_{side}") for side in ("left", "right")]
    return " / ".join(f"{a.min:.0f} to {a.max:.0f}°" if a else "-" for a in spans)


def keraal() -> None:
    """The KERAAL samples (docs/CAPTURE_SOURCES.md): each exercise made from its Kinect take (key
    poses suggested on it), its Kinect, Vicon and BlazePose files counted and measured; and the
    frames where the Kinect lost a shoulder (marked at import, `analysis.sources.ik.lost_shoulders`,
    left out of that shoulder's angles) and its shoulder elevation with them kept in."""
    recorders = ("Kinect", "Vicon", "BP")
    for exercise in ("CTK", "ELK", "RTK"):
        taken = {}
        for recorder in recorders:
            path = next(KERAAL.glob(f"G3-{recorder}-{exercise}-*"))
            taken[recorder] = read_recording(path.name, path.read_bytes())
        kinect = taken["Kinect"].motion
        poses = suggest_key_poses(kinect)
        model = build_model(kinect, poses.frames.tolist(), poses.types.tolist())
        found = {
            r: analyse(t.motion, model, lost_frames=t.lost_frames).summary for r, t in taken.items()
        }
        counts = " / ".join(str(found[r].repetition_count) for r in recorders)
        print(f"{exercise}: repetitions Kinect / Vicon / BlazePose {counts}")
        for name in KERAAL_ANGLES:
            spans = [found[r].clinical_angles.get(name) for r in recorders]
            text = " / ".join(f"{a.min:.0f} to {a.max:.0f}°" if a else "-" for a in spans)
            print(f"  {name}: {text}")
        lost = taken["Kinect"].lost_frames
        left_out = " / ".join(str(int(lost[f"{s}_shoulder"].sum())) if f"{s}_shoulder" in lost
                              else "0" for s in ("left", "right"))  # fmt: skip
        print(f"  Kinect frames with a lost shoulder (left / right): {left_out}; its shoulder "
              f"elevation with them kept in: {kept_in(kinect, model)}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--exercises", default=",".join(EXERCISES))
    parser.add_argument("--subjects", default="s01,s02")
    parser.add_argument("--models", default="kinect,vicon", help="what exercises are made from")
    parser.add_argument("--keraal", action="store_true", help="the KERAAL samples' table")
    args = parser.parse_args()
    if args.keraal:
        keraal()
        return
    subjects, made_from = tuple(args.subjects.split(",")), tuple(args.models.split(","))
    jobs = [(e, subjects, made_from) for e in args.exercises.split(",")]
    start = time.perf_counter()
    if args.jobs > 1:
        with multiprocessing.Pool(args.jobs) as pool:
            results = pool.map(run_exercise, jobs)
    else:
        results = [run_exercise(job) for job in jobs]
    pairs = [p for r in results for p in r]
    for p in pairs:
        print(
            f"{p.model:6s} {p.take:20s} count {p.counts[0]}/{p.counts[1]} "
            f"score {p.scores[0]:5.1f}/{p.scores[1]:5.1f} pass {p.passed[0]}/{p.passed[1]}"
        )
    print(table(pairs))
    print(f"{platform.processor() or platform.machine()}, {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
