"""On-line alignment on real data (issue 3, part b): UI-PRMD patient sessions against the tutor.

    .venv/bin/python -m bench.eval_alignment [--data data/ui-prmd] [--features directions]
        [--iterations 30] [--exercises m01,m02] [--jobs 3] [--ablation]
        [--markdown docs/sections/eval_alignment.md]

Part (a) of the issue's evaluation, exercise identification (LUT-DTW vs plain DTW), is
``bench/eval_identification.py`` (documented in docs/sections/eval_identification.md); this
script does not repeat it.

For each of the 10 exercises the tutor is subject s01's correct session (10 repetitions); the
patients are s02-s07, correct and incorrect (12 sessions of 10 repetitions). Every session is
aligned to the tutor by offline DTW, Open-End DTW (OE), Weight-Optimized OE-DTW (WOOE: path-length
weighting and CMA-ES joint weights) and forward plotting C with the Type V constraint (FP-C). The
tables give the share of patient frames mapped to a tutor frame of the same repetition
(``labels.csv`` start frames) and the median |on-line - offline| reference index in frames, each
on-line method against offline DTW with its own local cost.

Protocol choices (also printed):
- features: ``directions`` (default) are the bone directions of the 8 joints 003 uses (upper arms,
  forearms, thighs, shanks) from the global joint rotations, heading removed, Euclidean cost;
  ``quaternions`` are all 22 local joint rotations with the root's heading removed and the
  quaternion cost of paper 000 (eq 1). The roll about a bone, which Kinect does not measure,
  is noise in the quaternions and absent from the directions.
- WOOE's weights are learned on the other half of the patients (s02-s04 for s05-s07 and back),
  never on the evaluated subject, by CMA-ES with 30 generations of 6 parents / 12 offspring from
  w = 1 with an initial step of 0.3 (the paper: 300 generations, step 0.02; with a tenth of the
  generations a step of 0.02 leaves the weights near 1); segments for eq 5 are half
  repetitions (start -> end of range -> next start) from ``landmarks.csv``. With ``--ablation``,
  "OE+w" is Open-End DTW with weights learned the same way but without path-length weighting,
  to separate WOOE's two ingredients.
- Some subjects use the other side of the body: each session or its mirror image (left and right
  swapped), whichever has the lower offline DTW cost, is aligned to the tutor (a therapist would
  prescribe the side).
- FP-C: forecast window a third of the tutor's mean repetition, history 6 frames; "+PLW" chooses
  the forecast path by mean cost (the extension of paper 000 eq 3 used here; plain sums favour
  starting far ahead, so C skips frames).
"""

from __future__ import annotations

import argparse
import csv
import datetime as dt
import os
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from analysis.bvh import read
from analysis.dtw import DTWOptions, align
from analysis.dtw.joint_weights import JointWeightOptimizer
from analysis.dtw.metrics import offline_mapping, segment_labels
from analysis.kinematics import forward_kinematics as kin
from analysis.kinematics import quaternions as quat
from analysis.online.aligners import ForwardPlotAligner, ForwardPlotOptions, OpenEndAligner

EXERCISES = [f"m{k:02d}" for k in range(1, 11)]
PATIENTS = ["s02", "s03", "s04", "s05", "s06", "s07"]
FOLDS = (("s02", "s03", "s04"), ("s05", "s06", "s07"))
BONES = [
    "LeftUpperArm",
    "LeftForearm",
    "RightUpperArm",
    "RightForearm",
    "LeftUpperLeg",
    "LeftLowerLeg",
    "RightUpperLeg",
    "RightLowerLeg",
]
METHODS = ("offline", "OE", "WOOE", "FP-C+V", "FP-C+V+PLW")
ABLATION = "OE+w"


@dataclass(frozen=True)
class Take:
    """One session: features (F, d) for the tutor and its mirror image, labels per frame."""

    features: np.ndarray
    mirrored: np.ndarray
    reps: np.ndarray  # repetition index per frame
    segments: np.ndarray  # half-repetition index per frame (eq 5 training labels)
    subject: str


def swap_sides(names: list[str]) -> list[int]:
    return [
        names.index(n.replace("Left", "#").replace("Right", "Left").replace("#", "Right"))
        for n in names
    ]


def directions(motion: object, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Bone unit vectors (F, 8 * 3) of BONES in the heading-free world frame, and mirrored."""
    g = kin.global_rotations(motion)  # type: ignore[arg-type]
    heading = np.angle(np.mean(np.exp(1j * kin.heading_angles(motion))))  # type: ignore[arg-type]
    undo = quat.from_axis_angle("y", np.full(len(g), -heading))[:, None]
    parents = list(motion.skeleton.parents)  # type: ignore[attr-defined]
    idx = [names.index(b) for b in BONES]
    child = motion.skeleton.offsets[[parents.index(j) for j in idx]]  # type: ignore[attr-defined]
    v = quat.rotate(quat.multiply(undo, g[:, idx]), child / np.linalg.norm(child, axis=1)[:, None])
    mirror = v[:, swap_sides(BONES)] * np.array([-1.0, 1.0, 1.0])
    return v.reshape(len(v), -1), mirror.reshape(len(v), -1)


def quaternions(motion: object, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Local joint rotations (F, 22 * 4), root heading removed, and their mirror image."""
    r = kin.rotations(motion).copy()  # type: ignore[arg-type]
    heading = kin.heading_angles(motion)  # type: ignore[arg-type]
    r[:, 0] = quat.multiply(quat.from_axis_angle("y", -heading), r[:, 0])
    r = quat.make_continuous(r)
    mirror = r[:, swap_sides(names)] * np.array([1.0, 1.0, -1.0, -1.0])
    return r.reshape(len(r), -1), mirror.reshape(len(r), -1)


def load_take(data: Path, rel: str, labels: dict, landmarks: dict, kind: str) -> Take:  # type: ignore[type-arg]
    motion = read(data / rel)
    names = list(motion.skeleton.names)
    feats, mirror = (directions if kind == "directions" else quaternions)(motion, names)
    n = len(feats)
    reps = segment_labels(n, [int(s) for s in labels[rel]["rep_start_frames"].split(";")])
    cuts = [int(s) for s in landmarks[rel]["frames"].split(";")][:-1]
    return Take(feats, mirror, reps, segment_labels(n, cuts), rel.split("_")[1])


def read_csv(path: Path) -> dict[str, dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return {row["file"]: row for row in csv.DictReader(fh)}


def oriented(tutor: Take, take: Take, opt: DTWOptions) -> np.ndarray:
    """The session or its mirror image, whichever matches the tutor better offline."""
    frames = (take.features, take.mirrored)
    costs = [align(f, tutor.features, opt).normalized_cost for f in frames]
    return frames[int(costs[1] < costs[0])]


def train(
    tutor: Take, takes: list[Take], opt: DTWOptions, iterations: int, sigma: float
) -> np.ndarray:
    """CMA-ES joint weights for Open-End DTW with ``opt`` (paper 000, eq 5, half repetitions)."""
    frames = [oriented(tutor, t, opt) for t in takes]
    joints = len(BONES) if opt.cost == "euclidean" else None
    wo = JointWeightOptimizer(
        options=opt, iterations=iterations, sigma0=sigma, seed=0, joints=joints
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        wo.fit(tutor.features, tutor.segments, frames, [t.segments for t in takes])
    return wo.weights_


def stream(aligner: OpenEndAligner | ForwardPlotAligner, frames: np.ndarray) -> np.ndarray:
    return np.array([aligner.push(f) for f in frames])


def session_maps(
    tutor: np.ndarray, frames: np.ndarray, opt: DTWOptions, w: dict[str, np.ndarray], window: int
) -> dict[str, dict[str, np.ndarray]]:
    """Reference index per patient frame for every method, and each method's offline map.

    w: CMA-ES weights trained with path-length weighting ("WOOE") and, for the ablation,
    without ("OE+w")."""
    options = {m: opt for m in ("offline", "OE", "FP-C+V", "FP-C+V+PLW")}
    options |= {m: replace(opt, weights=tuple(v)) for m, v in w.items()}
    offline = {
        m: offline_mapping(align(frames, tutor, o).path, len(frames))
        for m, o in options.items()
        if m in ("offline", "WOOE", ABLATION)
    }
    fp = ForwardPlotOptions(method="C", window=window, history=6)
    tv = replace(opt, step="type-v")
    maps = {
        "offline": np.rint(offline["offline"]).astype(int),
        "OE": stream(OpenEndAligner(tutor, opt, keep_path=False), frames),
        "WOOE": stream(
            OpenEndAligner(
                tutor, replace(options["WOOE"], path_length_weighting=True), keep_path=False
            ),
            frames,
        ),
        "FP-C+V": stream(ForwardPlotAligner(tutor, fp, tv), frames),
        "FP-C+V+PLW": stream(
            ForwardPlotAligner(tutor, fp, replace(tv, path_length_weighting=True)), frames
        ),
    }
    if ABLATION in w:
        maps[ABLATION] = stream(OpenEndAligner(tutor, options[ABLATION], keep_path=False), frames)
    return {"maps": maps, "offline": {m: offline.get(m, offline["offline"]) for m in maps}}


def run_exercise(args: argparse.Namespace, ex: str, labels: dict, landmarks: dict) -> dict:  # type: ignore[type-arg]
    load = lambda rel: load_take(args.data, rel, labels, landmarks, args.features)  # noqa: E731
    tutor = load(f"sessions/{ex}_s01_correct.bvh.gz")
    takes = [
        load(f"sessions/{ex}_{s}_{lab}.bvh.gz")
        for s in PATIENTS
        for lab in ("correct", "incorrect")
    ]
    opt = DTWOptions(cost="euclidean" if args.features == "directions" else "quaternion")
    window = max(2, round(len(tutor.reps) / (tutor.reps.max() + 1) / 3))
    methods = methods_of(args)
    agree: dict[str, list[np.ndarray]] = {m: [] for m in methods}
    dev: dict[str, list[np.ndarray]] = {m: [] for m in methods}
    weights = []
    for train_on, test_on in (FOLDS, FOLDS[::-1]):
        train_takes = [t for t in takes if t.subject in train_on]
        plw = replace(opt, path_length_weighting=True)
        w = {"WOOE": train(tutor, train_takes, plw, args.iterations, args.sigma)}
        if args.ablation:
            w[ABLATION] = train(tutor, train_takes, opt, args.iterations, args.sigma)
        weights.append(w["WOOE"])
        for take in (t for t in takes if t.subject in test_on):
            r = session_maps(tutor.features, oriented(tutor, take, opt), opt, w, window)
            for m, mp in r["maps"].items():
                agree[m].append(take.reps == tutor.reps[mp])
                dev[m].append(np.abs(mp - r["offline"][m]))
    return {
        "agree": {m: float(np.mean(np.concatenate(v))) for m, v in agree.items()},
        "dev": {m: float(np.median(np.concatenate(v))) for m, v in dev.items()},
        "window": window,
        "weights": np.mean(weights, axis=0),
    }


def methods_of(args: argparse.Namespace) -> tuple[str, ...]:
    return (*METHODS, ABLATION) if args.ablation else METHODS


def tables(results: dict[str, dict], kind: str, methods: tuple[str, ...]) -> str:  # type: ignore[type-arg]
    head = "| exercise | " + " | ".join(methods) + " | WOOE >= OE | FP-C+V dev <= 10 |"
    lines = [
        "Share of patient frames mapped into the same repetition (higher is better), and",
        "median |on-line - offline DTW| in frames (same local cost), per exercise:",
        "",
        head,
        "|---" * (len(methods) + 3) + "|",
    ]
    for ex, r in results.items():
        cells = [f"{r['agree'][m]:.3f} / {r['dev'][m]:.0f}" for m in methods]
        ok1, ok2 = ("yes" if t else "NO" for t in _targets(r))
        lines.append(f"| {ex} | " + " | ".join(cells) + f" | {ok1} | {ok2} |")
    mean = {m: np.mean([r["agree"][m] for r in results.values()]) for m in methods}
    lines.append("| mean | " + " | ".join(f"{mean[m]:.3f}" for m in methods) + " | | |")
    windows = ", ".join(f"{e} {r['window']}" for e, r in results.items())
    passed = [sum(v) for v in zip(*(_targets(r) for r in results.values()), strict=True)]
    lines += [
        "",
        f"Features: {kind}. Cells: agreement / median deviation (frames, 30 fps). Targets met: "
        f"WOOE >= OE on {passed[0]} of {len(results)} exercises, FP-C + Type V within 10 "
        f"frames of offline DTW on {passed[1]} of {len(results)}.",
        f"FP-C windows (frames): {windows}",
    ]
    return "\n".join(lines)


def _targets(r: dict) -> tuple[bool, bool]:  # type: ignore[type-arg]
    return r["agree"]["WOOE"] >= r["agree"]["OE"], r["dev"]["FP-C+V"] <= 10


def evaluate(kind: str, ex: str, args: argparse.Namespace) -> dict:  # type: ignore[type-arg]
    """One exercise with one feature kind (a separate process with ``--jobs``)."""
    labels, landmarks = read_csv(args.data / "labels.csv"), read_csv(args.data / "landmarks.csv")
    r = run_exercise(argparse.Namespace(**{**vars(args), "features": kind}), ex, labels, landmarks)
    print(kind, ex, r["agree"], r["dev"], flush=True)
    return r


def main(argv: list[str] | None = None) -> str:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=Path("data/ui-prmd"))
    parser.add_argument("--features", default="directions", help="directions, quaternions or both")
    parser.add_argument("--iterations", type=int, default=30, help="CMA-ES generations")
    parser.add_argument("--exercises", default=",".join(EXERCISES))
    parser.add_argument("--sigma", type=float, default=0.3, help="CMA-ES initial step")
    parser.add_argument("--jobs", type=int, default=1, help="exercises evaluated in parallel")
    parser.add_argument("--ablation", action="store_true", help='also "OE+w" (see Protocol)')
    parser.add_argument("--markdown", help="also write the section to this file")
    args = parser.parse_args(argv)
    kinds = args.features.split(",")
    if any(k not in ("directions", "quaternions") for k in kinds):
        parser.error(f"unknown features {args.features!r}")
    t0, exercises = time.time(), args.exercises.split(",")
    todo = [(k, ex) for k in kinds for ex in exercises]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        done = list(pool.map(evaluate, *zip(*todo, strict=True), [args] * len(todo)))
    results = dict(zip(todo, done, strict=True))
    sections = [
        tables({ex: results[k, ex] for ex in exercises}, k, methods_of(args)) for k in kinds
    ]
    cmd = " ".join(
        ["python -m bench.eval_alignment", *(argv if argv is not None else sys.argv[1:])]
    )
    text = (
        f"## On-line alignment on UI-PRMD (bench/eval_alignment.py)\n\n`.venv/bin/{cmd}` - "
        f"{dt.date.today().isoformat()}, {os.cpu_count()} cores, {time.time() - t0:.0f} s.\n\n"
        + "\n\n".join(sections)
        + "\n\nProtocol:\n\n"
        + __doc__.split("Protocol choices (also printed):")[1].strip()
        + "\n"
    )
    print(text)
    if args.markdown:
        Path(args.markdown).write_text(text, encoding="utf-8")
    return text


if __name__ == "__main__":
    main()
