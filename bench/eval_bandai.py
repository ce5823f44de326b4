"""A new exercise from another rig, scored on the one scale: Bandai-Namco "raise both hands".

A cold-start model is built from one ``raise-up-both-hands`` take (key poses: the first frame,
the frame farthest from it, the last frame); every other take is analysed. Every both-hands take
should score above the pass threshold, every one-hand take below it, and the first correction of
a one-hand take should name the side of the arm that stayed down. The takes are read from
the shared data folder beside the checkout, at bench time only (CC BY-NC 4.0: never copied into
the repository).

    python -m bench.eval_bandai [--data SHARED/data/bandai-namco-motion-2/data]
           [--tutor dataset-2_raise-up-both-hands_normal_001.bvh]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from analysis.bvh import Motion, read
from analysis.kinematics import flatten, scaled_positions
from analysis.pipeline import FittedModel, analyse, build_model

DEFAULT = Path(__file__).resolve().parents[2] / "shared/data/bandai-namco-motion-2/data"
TUTOR = "dataset-2_raise-up-both-hands_normal_001.bvh"


def key_poses(motion: Motion) -> tuple[list[int], list[int]]:
    """Start, the pose farthest from it (end of range), end: one repetition per take."""
    points = flatten(scaled_positions(motion, list(range(len(motion.skeleton.names)))))
    peak = int(np.argmax(np.linalg.norm(points - points[0], axis=1)))
    return [0, peak, motion.n_frames - 1], [1, 2, 1]


def down_side(name: str) -> str:
    """The arm that stays down in a one-hand take ("" for both hands)."""
    if "raise-up-left-hand" in name:
        return "right"
    if "raise-up-right-hand" in name:
        return "left"
    return ""


def evaluate(path: Path, model: FittedModel) -> tuple[str, float, bool, str, bool]:
    """(take, score, as expected, first correction, names the arm that stayed down)."""
    summary = analyse(read(path), model).summary
    side = down_side(path.name)
    score = 0.0 if summary.score is None else summary.score  # None: does not fit the exercise
    expected = score < summary.pass_threshold if side else score >= summary.pass_threshold
    first = summary.advice.corrections[0] if summary.advice.corrections else None
    text = first.text if first else ""
    arm = ("arm", "elbow", "hand", "shoulder")
    named = bool(first) and first.part.startswith(side) and any(w in first.part for w in arm)
    return path.stem.removeprefix("dataset-2_"), score, expected, text, named or not side


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=DEFAULT)
    parser.add_argument("--tutor", default=TUTOR)
    args = parser.parse_args()
    tutor = read(args.data / args.tutor)
    model = build_model(tutor, *key_poses(tutor))
    threshold = model.components.papers.threshold.value
    print(f"Bandai-Namco raise-up evaluation, {time.strftime('%Y-%m-%d')}; tutor {args.tutor}, "
          f"pass threshold {threshold:.0f}\n")  # fmt: skip
    print("| take | score | expected side of 70 | first correction | names the arm left down |")
    print("|---|---|---|---|---|")
    rows = [evaluate(p, model) for p in sorted(args.data.glob("*.bvh")) if p.name != args.tutor]
    for name, score, ok, text, named in rows:
        print(f"| {name} | {score:.1f} | {'yes' if ok else '**no**'} | {text} | "
              f"{'yes' if named else '**no**'} |")  # fmt: skip
    both = [r for r in rows if "both-hands" in r[0]]
    one = [r for r in rows if "both-hands" not in r[0]]
    print(
        f"\nBoth-hands takes above the threshold: {sum(r[2] for r in both)}/{len(both)}; "
        f"one-hand takes below it: {sum(r[2] for r in one)}/{len(one)}; one-hand takes whose "
        f"first correction names the arm left down: {sum(r[4] for r in one)}/{len(one)}."
    )


if __name__ == "__main__":
    main()
