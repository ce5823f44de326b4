"""Candidate scoring features measured on both questions at once (issue 35, item 2): do the Kinect
and the Vicon side of UI-PRMD's paired takes score alike (`bench.eval_recorders`), and are
correct sessions still told from incorrect ones (`bench.eval_assessment`)?

Fast and approximate: each repetition is cut at the data set's labelled starts (no key-pose
search), and only the cold-start score of the tutor's repetitions is computed (no per-joint cap),
so a candidate can be tried in minutes rather than hours. Per candidate, the features of every
frame replace the product's (root-relative positions of every joint but the root over the body's
size, `analysis.pipeline.stages.scoring_features`); templates, the tutor's spread and the score
follow `analysis.assessment.scoring` unchanged. Printed per candidate: for the exercise made from
a Kinect session (s03) and from a Vicon one (s01), the share of pairs scoring within 5 points,
with the same pass/fail, and the median difference; on the 120 development sessions (tutor s01's
correct session, subjects s02–s07), the share judged as labelled, the mean score of correct and
incorrect sessions and the mean ROC-AUC per exercise; then the same with the pass margin
(`COLD_PASS_EXCESS`) refitted on those 120 sessions.

    python -m bench.eval_recorder_candidates [--exercises m01,m05] [--candidates positions,...]
"""

from __future__ import annotations

import argparse
import csv
import itertools
import statistics
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt
from sklearn.metrics import roc_auc_score

from analysis.assessment.scoring import (
    COLD_PASS_EXCESS,
    MOVING_SHARE,
    PASS_SCORE,
    SCALE_FLOOR,
    SHORTFALL_PASS,
    RepetitionScorer,
    cold_score,
    fit_scorer,
    repetition_features,
)
from analysis.bvh import Motion, read
from analysis.clinical.body import Body, find_body
from analysis.kinematics import flatten, relative_to_start, scaled_positions
from analysis.pipeline.model_fit import SCORING_FPS, tutor_repetitions
from analysis.pipeline.prepare import prepare
from bench.eval_recorders import DATA, EXERCISES, marks, vicon_key_poses, vicon_motion, vicon_rows

FloatArray = npt.NDArray[np.float64]
SUBJECTS = [f"s{k:02d}" for k in range(2, 8)]
MARGINS = np.round(np.arange(0.5, 4.01, 0.1), 2)
JUMP_SPEED = 1.5  # body sizes a second (about 5 m/s): no joint of these exercises moves faster
HELD_SPEED = 0.05  # body sizes a second: a joint this still before a jump was held, not moving


@dataclass
class Tutor:
    points: FloatArray  # (F, J, 3) scaled positions, every joint
    reps: list[tuple[int, int]]
    step: int
    fps: float
    body: Body
    motion: Motion


@dataclass
class Take:
    points: FloatArray  # (F, J, 3) in the tutor's joint order, at its rate
    repetitions: list[tuple[int, int]]


Parts = list[tuple[float, float]]  # per repetition: excess in tutor units, largest shortfall
Features = Callable[[FloatArray, Tutor], FloatArray]  # (F, J, 3) -> (F, K, 3)


@dataclass
class Measured:
    pairs: list[tuple[str, Parts, Parts]] = field(default_factory=list)  # made from, Kinect, Vicon
    sessions: list[tuple[str, Parts, bool]] = field(default_factory=list)  # exercise, parts, ok
    bridged: dict[str, int] = field(default_factory=dict)  # joint-frames bridged, per recorder


def tutor(motion: Motion, frames: list[int], types: list[int]) -> Tutor:
    points = scaled_positions(motion, list(range(len(motion.skeleton.names))))
    step = max(1, round(motion.fps / SCORING_FPS))
    reps = tutor_repetitions(frames, types)
    return Tutor(points, reps, step, motion.fps, find_body(motion.skeleton), motion)


def take(motion: Motion, model: Tutor, starts: list[int]) -> Take:
    prepared = prepare(motion, model.motion.skeleton, model.fps, 1.0)
    ratio = model.fps / motion.fps
    bounds = [round(f * ratio) for f in starts] + [prepared.n_frames]
    return Take(prepared.points, [(a, b - 1) for a, b in itertools.pairwise(bounds)])


def starts_of(text: str) -> list[int]:
    return [int(v) for v in text.split(";")]


def positions(points: FloatArray, model: Tutor) -> FloatArray:
    """The product's features: every joint but the root."""
    return points[:, 1:]


def bridged(points: FloatArray, model: Tutor) -> FloatArray:
    """The product's features after bridging each joint's tracking losses: a frame the joint
    reaches faster than `JUMP_SPEED`, and the frames it was held still just before, are
    interpolated from the frames around them."""
    return bridge_jumps(points, model.fps)[0][:, 1:]


def bridge_jumps(points: FloatArray, fps: float) -> tuple[FloatArray, int]:
    """(F, J, 3) with jumps bridged, and how many joint-frames were bridged."""
    out = points.astype(np.float64, copy=True)
    speed = np.linalg.norm(np.diff(out, axis=0), axis=-1) * fps  # (F - 1, J)
    count = 0
    for joint in range(out.shape[1]):
        lost = np.zeros(out.shape[0], dtype=bool)
        for frame in np.flatnonzero(speed[:, joint] > JUMP_SPEED) + 1:
            lost[frame] = True
            held = frame - 1
            while held > 0 and speed[held - 1, joint] < HELD_SPEED:
                lost[held] = True
                held -= 1
        if lost.any() and not lost.all():
            good = np.flatnonzero(~lost)
            for axis in range(3):
                out[lost, joint, axis] = np.interp(
                    np.flatnonzero(lost), good, out[good, joint, axis]
                )
            count += int(lost.sum())
    return out, count


def _unit(v: FloatArray) -> FloatArray:
    return np.asarray(v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9))


def trunk_frames(points: FloatArray, body: Body) -> FloatArray:
    """(F, 3, 3): columns forward, up (pelvis → neck) and the hip line made perpendicular."""
    joints = body.joints
    up = _unit(points[:, joints.get("neck", joints.get("chest", 0))] - points[:, joints["pelvis"]])
    side = points[:, joints["hip_right"]] - points[:, joints["hip_left"]]
    side = _unit(side - np.sum(side * up, axis=-1, keepdims=True) * up)
    return np.stack((np.cross(up, side), up, side), axis=-1)


def directions(points: FloatArray, model: Tutor, feet: bool = True) -> FloatArray:
    """Each limb segment's direction in the trunk's frame (anatomical: where the joint centres
    sit along the limb does not count), then the trunk's up and forward axes."""
    frames = trunk_frames(points.astype(np.float64), model.body)
    out = []
    for name, (a, b) in model.body.limbs.items():
        if feet or not name.startswith("foot"):
            v = _unit(points[:, b] - points[:, a])
            out.append(np.einsum("fij,fi->fj", frames, v))
    out += [frames[:, :, 1], frames[:, :, 0]]
    return np.stack(out, axis=1)


def amplitude_scale(scorer: RepetitionScorer) -> RepetitionScorer:
    """The excess's unit from the movement's amplitude (a tenth of the mean reach of the joints
    the tutor moves) rather than the tutor's repetition-to-repetition distance."""
    reach = scorer.tutor_reach
    assert reach is not None
    moving = reach >= MOVING_SHARE * reach.max()
    return replace(scorer, scale=0.1 * float(reach[moving].mean()))


@dataclass(frozen=True)
class Candidate:
    """Per-frame features in place of the product's, and a change to the fitted scorer."""

    features: Features
    rescale: Callable[[RepetitionScorer], RepetitionScorer] = lambda s: s


CANDIDATES = {
    "positions": Candidate(positions),
    "bridged": Candidate(bridged),
    "directions": Candidate(directions),
    "directions-no-feet": Candidate(lambda p, m: directions(p, m, feet=False)),
    "amplitude-unit": Candidate(positions, amplitude_scale),
}


def parts(candidate: Candidate, model: Tutor, takes: list[Take]) -> list[Parts]:
    feats = candidate.features(model.points, model)
    templates = [relative_to_start(flatten(feats[a : b + 1]))[:: model.step] for a, b in model.reps]
    scorer = candidate.rescale(fit_scorer(templates))
    out = []
    for one in takes:
        moved = candidate.features(one.points, model)
        found = []
        for a, b in one.repetitions:
            segment = relative_to_start(flatten(moved[a : b + 1]))[:: model.step]
            f = repetition_features(segment, templates)
            over = np.maximum(f[: scorer.mean.size] - scorer.mean, 0.0)
            excess = float(np.mean(over)) / max(scorer.scale, SCALE_FLOOR)
            found.append((excess, float(scorer.shortfall(f).max())))
        out.append(found)
    return out


def session_score(found: Parts, margin: float) -> float:
    badness = [max(e / margin, s / SHORTFALL_PASS) for e, s in found]
    return float(np.mean([cold_score(b) for b in badness])) if badness else 0.0


def measure(exercise: str, candidates: dict[str, Candidate]) -> dict[str, Measured]:
    with open(DATA / "labels.csv") as handle:
        labels = {r["file"]: starts_of(r["rep_start_frames"]) for r in csv.DictReader(handle)}
    kinect_name = f"sessions/{exercise}_s03_correct.bvh.gz"
    models = {
        "kinect": tutor(read(DATA / kinect_name), *marks()[kinect_name]),
        "vicon": tutor(*vicon_key_poses(exercise)),
    }
    paired: dict[str, list[tuple[Take, Take]]] = {"kinect": [], "vicon": []}
    for name, row in sorted(vicon_rows().items()):
        if row["exercise"] != exercise:
            continue
        kinect, vicon = read(DATA / row["kinect_session"]), vicon_motion(row["file"])
        for made_from, model in models.items():
            if made_from == "vicon" and name == f"{exercise}_s01_correct":
                continue  # the take the exercise was made from
            paired[made_from].append((
                take(kinect, model, labels[row["kinect_session"]]),
                take(vicon, model, starts_of(row["rep_start_frames"])),
            ))  # fmt: skip
    dev_name = f"sessions/{exercise}_s01_correct.bvh.gz"
    dev = tutor(read(DATA / dev_name), *marks()[dev_name])
    names = [
        f"sessions/{exercise}_{s}_{lab}.bvh.gz"
        for s in SUBJECTS
        for lab in ("correct", "incorrect")
    ]
    sessions = [take(read(DATA / n), dev, labels[n]) for n in names]
    k_fps = models["kinect"].fps
    counts = {
        "Kinect takes": sum(bridge_jumps(k.points, k_fps)[1] for k, _ in paired["kinect"]),
        "Vicon takes": sum(bridge_jumps(v.points, k_fps)[1] for _, v in paired["kinect"]),
        "development sessions": sum(bridge_jumps(s.points, dev.fps)[1] for s in sessions),
    }
    out = {}
    for label, candidate in candidates.items():
        got = Measured(bridged=counts)
        for made_from, model in models.items():
            kin = parts(candidate, model, [k for k, _ in paired[made_from]])
            vic = parts(candidate, model, [v for _, v in paired[made_from]])
            got.pairs += [(made_from, a, b) for a, b in zip(kin, vic, strict=True)]
        for n, found in zip(names, parts(candidate, dev, sessions), strict=True):
            got.sessions.append((exercise, found, not n.endswith("_incorrect.bvh.gz")))
        out[label] = got
    return out


def agreement(got: Measured, margin: float) -> float:
    return float(
        np.mean([(session_score(f, margin) >= PASS_SCORE) == ok for _, f, ok in got.sessions])
    )


def report(label: str, got: Measured, margin: float) -> str:
    cells = []
    for made_from in ("kinect", "vicon"):
        scores = [
            (session_score(a, margin), session_score(b, margin))
            for m, a, b in got.pairs
            if m == made_from
        ]
        within = np.mean([abs(a - b) <= 5 for a, b in scores])
        same = np.mean([(a >= PASS_SCORE) == (b >= PASS_SCORE) for a, b in scores])
        median = statistics.median(abs(a - b) for a, b in scores)
        cells.append(f"{within:.0%} | {same:.0%} | {median:.1f}")
    scored = [(e, session_score(f, margin), ok) for e, f, ok in got.sessions]
    good = np.mean([s for _, s, ok in scored if ok])
    bad = np.mean([s for _, s, ok in scored if not ok])
    aucs = [
        roc_auc_score([ok for x, _, ok in scored if x == e], [s for x, s, _ in scored if x == e])
        for e in sorted({e for e, _, _ in scored})
    ]
    return (
        f"| {label} | {margin:.1f} | {' | '.join(cells)} | {agreement(got, margin):.1%} | "
        f"{good:.1f} / {bad:.1f} | {np.mean(aucs):.3f} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--exercises", default=",".join(EXERCISES))
    parser.add_argument("--candidates", default=",".join(CANDIDATES))
    args = parser.parse_args()
    chosen = {c: CANDIDATES[c] for c in args.candidates.split(",")}
    merged = {c: Measured() for c in chosen}
    bridged_counts: dict[str, int] = {}
    for exercise in args.exercises.split(","):
        for label, got in measure(exercise, chosen).items():
            merged[label].pairs += got.pairs
            merged[label].sessions += got.sessions
            bridged = got.bridged
        for name, count in bridged.items():
            bridged_counts[name] = bridged_counts.get(name, 0) + count
        print(f"{exercise} measured", flush=True)
    print(
        "\n| candidate | margin | Kinect-made: within 5 | same pass/fail | median difference | "
        "Vicon-made: within 5 | same pass/fail | median difference | sessions as labelled | "
        "mean correct / incorrect | AUC |\n|---|---|---|---|---|---|---|---|---|---|---|"
    )
    for label, got in merged.items():
        print(report(label, got, COLD_PASS_EXCESS))
        refit = max(MARGINS, key=lambda m: (agreement(got, float(m)), -abs(m - COLD_PASS_EXCESS)))
        print(report(f"{label}, margin refitted", got, float(refit)))
    print(f"\nJoint-frames bridged (faster than {JUMP_SPEED} body sizes/s, or held before such a "
          f"jump): {bridged_counts}")  # fmt: skip


if __name__ == "__main__":
    main()
