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
incorrect sessions and the mean ROC-AUC per exercise; the same AUC on the paired takes scored
against the other recorder's tutor (Vicon takes against the Kinect-made exercise, Kinect takes
against the Vicon-made one: a candidate that treats the recorders differently must still tell
correct from incorrect there); last, the median difference of all 70 pairs
over the gap between the mean correct and incorrect session (a candidate that only compresses the
scale brings the recorders closer in points, not against that gap); then the same with the pass
margin (`COLD_PASS_EXCESS`) refitted on those 120 sessions.

The third round's candidates (a recorder-aware filter before the features, a joint's excess capped
or left out, the median repetition) are in `bench/recorder_candidate_features.py`. ``--cache DIR``
keeps each exercise's prepared takes there, so a second run only scores.

    python -m bench.eval_recorder_candidates [--exercises m01,m05] [--candidates positions,...]
        [--cache /tmp/recorder-takes]
"""

from __future__ import annotations

import argparse
import statistics
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

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
    tutor_statistics,
)
from analysis.kinematics import flatten, relative_to_start
from bench.eval_recorders import EXERCISES, vicon_rows
from bench.recorder_candidate_features import (
    JUMP_SPEED,
    bridge_jumps,
    capped_mean,
    carried,
    jumping_joints,
    low_passed,
    trimmed_mean,
    trunk_frames,
    unit,
)
from bench.recorder_candidate_takes import Take, Tutor, load

FloatArray = npt.NDArray[np.float64]
MARGINS = np.round(np.arange(0.5, 4.01, 0.1), 2)


Parts = list[tuple[float, float]]  # per repetition: excess in tutor units, largest shortfall
Features = Callable[[FloatArray, Tutor], FloatArray]  # (F, J, 3) -> (F, K, 3)
Prefilter = Callable[[FloatArray, str, Tutor], FloatArray]  # points, recorder, tutor -> points


@dataclass
class Measured:
    # exercise, made from, Kinect, Vicon, whether the take was done correctly
    pairs: list[tuple[str, str, Parts, Parts, bool]] = field(default_factory=list)
    sessions: list[tuple[str, Parts, bool]] = field(default_factory=list)  # exercise, parts, ok
    bridged: dict[str, int] = field(default_factory=dict)  # joint-frames bridged, per recorder
    aggregate: str = "mean"  # how a recording's score comes from its repetitions' scores


def positions(points: FloatArray, model: Tutor) -> FloatArray:
    """The product's features: every joint but the root."""
    return points[:, 1:]


HANDS = ("LeftHand", "RightHand")
ENDS = ("HeadTip", "LeftToes", "RightToes")  # the chains' ends a Vicon rig does not have


def without(points: FloatArray, model: Tutor, names: tuple[str, ...]) -> FloatArray:
    """The product's features with the joints ``names`` left out."""
    skeleton = model.motion.skeleton.names
    return points[:, [j for j in range(1, len(skeleton)) if skeleton[j] not in names]]


def bridged(points: FloatArray, model: Tutor) -> FloatArray:
    """The product's features after bridging each joint's tracking losses: a frame the joint
    reaches faster than `JUMP_SPEED`, and the frames it was held still just before, are
    interpolated from the frames around them."""
    return bridge_jumps(points, model.fps)[0][:, 1:]


def directions(points: FloatArray, model: Tutor, feet: bool = True) -> FloatArray:
    """Each limb segment's direction in the trunk's frame (anatomical: where the joint centres
    sit along the limb does not count), then the trunk's up and forward axes."""
    frames = trunk_frames(points.astype(np.float64), model.body)
    out = []
    for name, (a, b) in model.body.limbs.items():
        if feet or not name.startswith("foot"):
            v = unit(points[:, b] - points[:, a])
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


def unfiltered(points: FloatArray, recorder: str, model: Tutor) -> FloatArray:
    return points


def vicon_low_passed(points: FloatArray, recorder: str, model: Tutor) -> FloatArray:
    """Vicon's takes (and tutor) seen at the Kinect's bandwidth; Kinect takes as they are."""
    return low_passed(points, model.fps) if recorder == "vicon" else points


def shoulders_carried(points: FloatArray, recorder: str, model: Tutor) -> FloatArray:
    return carried(points, model.body, ("shoulder_left", "shoulder_right"))


def girdle_carried(points: FloatArray, recorder: str, model: Tutor) -> FloatArray:
    """Shoulders and collars (where the rig has them) carried by the trunk."""
    names = ("shoulder_left", "shoulder_right", "collar_left", "collar_right")
    return carried(points, model.body, names)


@dataclass(frozen=True)
class Candidate:
    """Per-frame features in place of the product's, and a change to the fitted scorer; the
    third round's: a filter per recorder before the features, how the joints' excesses make one
    (``reduce``, on excesses in score units), the speed above which a joint of a repetition is
    left out of it, and how a recording's score comes from its repetitions'."""

    features: Features
    rescale: Callable[[RepetitionScorer], RepetitionScorer] = lambda s: s
    prefilter: Prefilter = unfiltered
    reduce: Callable[[FloatArray], float] = lambda over: float(np.mean(over))
    jump_limit: float | None = None
    aggregate: str = "mean"
    start_frames: int = 1  # the start pose: the mean of the repetition's first frames
    standardised: bool = False  # each joint's excess over its own tutor spread (`spread`)
    own_spread: str = ""  # "max" / "sum": the take's own repetition-to-repetition deviation too
    cross_allowance: float = 0.0  # body sizes: a take from the other recorder may deviate more


CANDIDATES = {
    "positions": Candidate(positions),
    "bridged": Candidate(bridged),
    "directions": Candidate(directions),
    "directions-no-feet": Candidate(lambda p, m: directions(p, m, feet=False)),
    "amplitude-unit": Candidate(positions, amplitude_scale),
    "median-repetition": Candidate(positions, aggregate="median"),
    "cross-allowance-0.5%": Candidate(positions, cross_allowance=0.005),
    "cross-allowance-1%": Candidate(positions, cross_allowance=0.01),
    "carried-low-passed-lost-left-out": Candidate(
        positions,
        prefilter=lambda p, r, m: girdle_carried(vicon_low_passed(p, r, m), r, m),
        jump_limit=JUMP_SPEED,
    ),
    "carried-low-passed": Candidate(
        positions, prefilter=lambda p, r, m: girdle_carried(vicon_low_passed(p, r, m), r, m)
    ),
    "own-spread-max": Candidate(positions, own_spread="max"),
    "own-spread-quadrature": Candidate(positions, own_spread="sum"),
    "start-of-5-frames": Candidate(positions, start_frames=5),
    "start-of-10-frames": Candidate(positions, start_frames=10),
    "per-joint-unit": Candidate(positions, standardised=True),
    "vicon-low-passed-0.1": Candidate(
        positions, prefilter=lambda p, r, m: low_passed(p, m.fps, 0.1) if r == "vicon" else p
    ),
    "both-low-passed-0.1": Candidate(
        positions, prefilter=lambda p, r, m: low_passed(p, m.fps, 0.1)
    ),
    "shoulders-carried": Candidate(positions, prefilter=shoulders_carried),
    "girdle-carried": Candidate(positions, prefilter=girdle_carried),
    "vicon-low-passed": Candidate(positions, prefilter=vicon_low_passed),
    "lost-joints-left-out": Candidate(positions, jump_limit=JUMP_SPEED),
    "joint-capped-2": Candidate(positions, reduce=lambda over: capped_mean(over, 2.0)),
    "joint-capped-1.5": Candidate(positions, reduce=lambda over: capped_mean(over, 1.5)),
    "joint-capped-2.5": Candidate(positions, reduce=lambda over: capped_mean(over, 2.5)),
    "joint-capped-3": Candidate(positions, reduce=lambda over: capped_mean(over, 3.0)),
    "joint-capped-2-lost-left-out": Candidate(
        positions, reduce=lambda over: capped_mean(over, 2.0), jump_limit=JUMP_SPEED
    ),
    "joint-capped-5": Candidate(positions, reduce=lambda over: capped_mean(over, 5.0)),
    "hands-left-out": Candidate(lambda p, m: without(p, m, HANDS)),
    "ends-left-out": Candidate(lambda p, m: without(p, m, HANDS + ENDS)),
    "worst-joint-left-out": Candidate(positions, reduce=lambda over: trimmed_mean(over, 1)),
}


def parts(candidate: Candidate, model: Tutor, takes: list[Take]) -> list[Parts]:
    feats = candidate.features(candidate.prefilter(model.points, model.recorder, model), model)
    n = candidate.start_frames
    templates = [from_start(flatten(feats[a : b + 1]), n)[:: model.step] for a, b in model.reps]
    scorer = candidate.rescale(fit_scorer(templates))
    out = []
    for one in takes:
        points = candidate.prefilter(one.points, one.recorder, model)
        moved = candidate.features(points, model)
        found = []
        segments = [
            from_start(flatten(moved[a : b + 1]), n)[:: model.step] for a, b in one.repetitions
        ]
        allowed = scorer.mean
        if one.recorder != model.recorder:
            allowed = np.sqrt(allowed**2 + candidate.cross_allowance**2)
        if candidate.own_spread and len(segments) >= 2:
            own = tutor_statistics(segments)[0]
            if candidate.own_spread == "max":
                allowed = np.maximum(allowed, own)
            else:
                allowed = np.sqrt(allowed**2 + own**2)
        for (a, b), segment in zip(one.repetitions, segments, strict=True):
            f = repetition_features(segment, templates)
            over = np.maximum(f[: scorer.mean.size] - allowed, 0.0)
            over /= scorer.spread if candidate.standardised else max(scorer.scale, SCALE_FLOOR)
            if candidate.jump_limit is not None and over.size == points.shape[1] - 1:
                lost = jumping_joints(points[a : b + 1, 1:], model.fps, candidate.jump_limit)
                over = over[~lost] if not lost.all() else over
            found.append((candidate.reduce(over), float(scorer.shortfall(f).max())))
        out.append(found)
    return out


def from_start(rows: FloatArray, frames: int) -> FloatArray:
    """`relative_to_start` with the start pose the mean of the first ``frames`` rows."""
    return rows - rows[:frames].mean(axis=0) if frames > 1 else relative_to_start(rows)


def session_score(found: Parts, margin: float, aggregate: str = "mean") -> float:
    badness = [max(e / margin, s / SHORTFALL_PASS) for e, s in found]
    if not badness:
        return 0.0
    scores = [cold_score(b) for b in badness]
    return float(np.median(scores) if aggregate == "median" else np.mean(scores))


def correct_pairs(exercise: str) -> list[tuple[str, bool]]:
    """Per paired take in `load`'s order: the tutor it is scored against, whether it is correct."""
    return [
        (made_from, not name.endswith("_incorrect"))
        for name, row in sorted(vicon_rows().items())
        if row["exercise"] == exercise
        for made_from in ("kinect", "vicon")
        if not (made_from == "vicon" and name == f"{exercise}_s01_correct")
    ]


def measure(
    exercise: str, candidates: dict[str, Candidate], cache: Path | None = None
) -> dict[str, Measured]:
    got_in = load(exercise, cache)
    models, paired, dev = got_in.models, got_in.paired, got_in.dev
    k_fps = models["kinect"].fps
    counts = {
        "Kinect takes": sum(bridge_jumps(k.points, k_fps)[1] for k, _ in paired["kinect"]),
        "Vicon takes": sum(bridge_jumps(v.points, k_fps)[1] for _, v in paired["kinect"]),
        "development sessions": sum(bridge_jumps(s.points, dev.fps)[1] for s in got_in.sessions),
    }
    out = {}
    for label, candidate in candidates.items():
        got = Measured(bridged=counts, aggregate=candidate.aggregate)
        for made_from, model in models.items():
            kin = parts(candidate, model, [k for k, _ in paired[made_from]])
            vic = parts(candidate, model, [v for _, v in paired[made_from]])
            done = [c for m, c in correct_pairs(exercise) if m == made_from]
            got.pairs += [
                (exercise, made_from, a, b, c) for a, b, c in zip(kin, vic, done, strict=True)
            ]
        for n, found in zip(got_in.names, parts(candidate, dev, got_in.sessions), strict=True):
            got.sessions.append((exercise, found, not n.endswith("_incorrect.bvh.gz")))
        out[label] = got
    return out


def agreement(got: Measured, margin: float) -> float:
    return float(
        np.mean(
            [
                (session_score(f, margin, got.aggregate) >= PASS_SCORE) == ok
                for _, f, ok in got.sessions
            ]
        )
    )


def mean_auc(scored: list[tuple[str, float, bool]]) -> float:
    """The mean over groups (exercises) of the ROC-AUC of (group, score, correct) rows."""
    aucs = []
    for group in sorted({g for g, _, _ in scored}):
        rows = [(s, ok) for g, s, ok in scored if g == group]
        aucs.append(roc_auc_score([ok for _, ok in rows], [s for s, _ in rows]))
    return float(np.mean(aucs))


def report(label: str, got: Measured, margin: float) -> str:
    cells, gaps = [], []
    for made_from in ("kinect", "vicon"):
        scores = [
            (session_score(a, margin, got.aggregate), session_score(b, margin, got.aggregate))
            for _, m, a, b, _ in got.pairs
            if m == made_from
        ]
        within = np.mean([abs(a - b) <= 5 for a, b in scores])
        same = np.mean([(a >= PASS_SCORE) == (b >= PASS_SCORE) for a, b in scores])
        median = statistics.median(abs(a - b) for a, b in scores)
        gaps += [abs(a - b) for a, b in scores]
        cells.append(f"{within:.0%} | {same:.0%} | {median:.1f}")
    scored = [(e, session_score(f, margin, got.aggregate), ok) for e, f, ok in got.sessions]
    good = np.mean([s for _, s, ok in scored if ok])
    bad = np.mean([s for _, s, ok in scored if not ok])
    aucs = mean_auc(scored)
    across = [  # the other recorder's side: Vicon takes against a Kinect tutor, and conversely
        (f"{e} {m}", session_score(b if m == "kinect" else a, margin, got.aggregate), ok)
        for e, m, a, b, ok in got.pairs
    ]
    return (
        f"| {label} | {margin:.1f} | {' | '.join(cells)} | {agreement(got, margin):.1%} | "
        f"{good:.1f} / {bad:.1f} | {aucs:.3f} | {mean_auc(across):.3f} | "
        f"{np.median(gaps) / (good - bad):.2f} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--exercises", default=",".join(EXERCISES))
    parser.add_argument("--candidates", default=",".join(CANDIDATES))
    parser.add_argument("--cache", type=Path, help="keep the prepared takes here (pickles)")
    args = parser.parse_args()
    chosen = {c: CANDIDATES[c] for c in args.candidates.split(",")}
    merged = {c: Measured(aggregate=chosen[c].aggregate) for c in chosen}
    bridged_counts: dict[str, int] = {}
    for exercise in args.exercises.split(","):
        for label, got in measure(exercise, chosen, args.cache).items():
            merged[label].pairs += got.pairs
            merged[label].sessions += got.sessions
            bridged = got.bridged
        for name, count in bridged.items():
            bridged_counts[name] = bridged_counts.get(name, 0) + count
        print(f"{exercise} measured", flush=True)
    print(
        "\n| candidate | margin | Kinect-made: within 5 | same pass/fail | median difference | "
        "Vicon-made: within 5 | same pass/fail | median difference | sessions as labelled | "
        "mean correct / incorrect | AUC | AUC across recorders | median difference / gap |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    )
    for label, got in merged.items():
        print(report(label, got, COLD_PASS_EXCESS))
        refit = max(MARGINS, key=lambda m: (agreement(got, float(m)), -abs(m - COLD_PASS_EXCESS)))
        print(report(f"{label}, margin refitted", got, float(refit)))
    print(f"\nJoint-frames bridged (faster than {JUMP_SPEED} body sizes/s, or held before such a "
          f"jump): {bridged_counts}")  # fmt: skip


if __name__ == "__main__":
    main()
