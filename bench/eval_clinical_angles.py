"""Clinical angles a clinician would sign (issue 26 item 1): the figures docs/sections/clinical.md
quotes, measured on the repository's data and, when it is beside the checkout, the shared
Bandai-Namco sample (read at bench time only: CC BY-NC, never copied into the repository).

1. UI-PRMD shoulder abductions (m07, 14 sessions): shoulder elevation against the angle between
   upper arm and trunk (neck → waist) from the joint positions, per frame; the moving arm's
   largest elevation, abduction and flexion.
2. Every recording of data/ui-prmd and data/rigs: the angles measured, the frames left out
   beyond the body's limits, and the angles not measurable (by reason).
3. Bandai-Namco raise-up takes: each take's first frame (the actor standing before the raise),
   hips, knees, shoulders and trunk in degrees.
4. Issue 35: every development session and rig, every amount a finding or correction can be
   made of (a clinical angle's or a compensation's range over the recording, which bounds every
   range difference and posture difference between two of its stretches) against the measure's
   physiological span (`analysis.clinical.physiological_span`): the count beyond must be 0;
   and the compensations not measurable (beyond a body, or noisier than they would flag).

    .venv/bin/python -m bench.eval_clinical_angles [--bandai SHARED/data/bandai-namco-motion-2/data]
"""

from __future__ import annotations

import argparse
import time
from collections import Counter
from pathlib import Path

import numpy as np

from analysis.assessment.compensations import compensation_measures
from analysis.bvh import Motion, read
from analysis.clinical import measure, physiological_span
from analysis.clinical.body import find_body, take_vertical
from analysis.clinical.labels import split_side
from analysis.kinematics import kinematics, positions

ROOT = Path(__file__).resolve().parents[1]
UI_PRMD = ROOT / "data" / "ui-prmd"
BANDAI = ROOT.parent / "shared/data/bandai-namco-motion-2/data"
STANDING = ("hip_flexion", "hip_abduction", "knee_flexion", "shoulder_elevation")


def arm_to_trunk(motion: Motion, side: str) -> np.ndarray:
    at = {n: i for i, n in enumerate(motion.skeleton.names)}
    pos = positions(motion)
    arm = pos[:, at[f"{side.capitalize()}Forearm"]] - pos[:, at[f"{side.capitalize()}UpperArm"]]
    down = pos[:, at["Waist"]] - pos[:, at["Neck"]]
    cos = np.sum(arm * down, -1) / np.linalg.norm(arm, axis=-1) / np.linalg.norm(down, axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def abductions() -> None:
    print("| session | moving arm | largest arm-to-trunk (positions) | elevation | abduction | "
          "flexion | worst frame difference, both arms |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for path in sorted(UI_PRMD.glob("sessions/m07_*.bvh.gz")):
        motion = read(path)
        series = measure(motion).series
        truth = {s: arm_to_trunk(motion, s) for s in ("left", "right")}
        worst = max(
            float(np.nanmax(np.abs(series[f"shoulder_elevation_{s}"] - truth[s]))) for s in truth
        )
        side = max(truth, key=lambda s: truth[s].max())
        kinds = ("elevation", "abduction", "flexion")
        top = {k: np.nanmax(series[f"shoulder_{k}_{side}"]) for k in kinds}
        print(f"| {path.name.split('.')[0]} | {side} | {truth[side].max():.1f}° | "
              f"{top['elevation']:.1f}° | {top['abduction']:.1f}° | {top['flexion']:.1f}° | "
              f"{worst:.2f}° |")  # fmt: skip


def coverage() -> None:
    paths = sorted([*UI_PRMD.glob("*/*.bvh.gz"), *(ROOT / "data" / "rigs").glob("*.bvh")])
    measured, reasons, left_out = 0, Counter(), Counter()
    for path in paths:
        result = measure(read(path))
        measured += len(result.series)
        left_out.update(n for n, v in result.series.items() if np.isnan(v).any())
        for name, note in result.notes.items():
            kind = "beyond the body's limits" if "beyond" in note else note.split(": ", 1)[1]
            reasons[(kind, split_side(name)[0])] += 1
    print(f"\n{len(paths)} recordings: {measured} angles measured; with frames left out beyond "
          f"the limits: {sum(left_out.values())}; not measurable:")  # fmt: skip
    for (kind, name), count in sorted(reasons.items()):
        print(f"- {name}: {count} ({kind})")


def bandai(folder: Path) -> None:
    if not folder.is_dir():
        print(f"\n(no Bandai-Namco sample at {folder})")
        return
    print("\n| Bandai-Namco take, first frame | hip flexion L/R | hip abduction L/R | "
          "knee flexion L/R | shoulder elevation L/R | trunk flexion |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    for path in sorted(folder.glob("*.bvh")):
        s = measure(read(path)).series
        pair = [f"{s[f'{n}_left'][0]:.1f} / {s[f'{n}_right'][0]:.1f}" for n in STANDING]
        print(f"| {path.stem.removeprefix('dataset-2_')} | {' | '.join(pair)} | "
              f"{s['trunk_flexion'][0]:.1f} |")  # fmt: skip


def amounts() -> None:
    paths = sorted([*UI_PRMD.glob("sessions/*.bvh.gz"), *(ROOT / "data" / "rigs").glob("*.bvh")])
    checked, beyond, notes = 0, [], Counter()
    for path in paths:
        motion = read(path)
        series = dict(measure(motion).series)
        body = find_body(motion.skeleton)
        pos = kinematics(motion).positions
        up = body.up if body.upright else take_vertical(pos, body)
        kept, why = compensation_measures(pos, body.joints, up)
        series.update(kept)
        notes.update(n.split(":")[0] for n in why.values())
        for name, values in series.items():
            if np.isfinite(values).any():
                checked += 1
                if float(np.nanmax(values) - np.nanmin(values)) > physiological_span(name):
                    beyond.append(f"{path.name} {name}")
    print(f"\n{len(paths)} recordings (sessions and rigs): {checked} measures' ranges checked, "
          f"{len(beyond)} beyond the physiological span {beyond[:5]}; compensations left out: "
          f"{dict(notes)}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--bandai", type=Path, default=BANDAI)
    parser.add_argument("--amounts", action="store_true", help="only item 4 (issue 35)")
    args = parser.parse_args()
    if args.amounts:
        amounts()
        return
    print(f"Clinical angles, {time.strftime('%Y-%m-%d')}\n")
    abductions()
    coverage()
    amounts()
    bandai(args.bandai)


if __name__ == "__main__":
    main()
