"""Check positions() against the suite's scipy forward kinematics on every BVH file of a folder.

The suite checks the UI-PRMD copies kept in the repository; this covers data that may not be
copied into it (the Bandai-Namco set is non-commercial), read from a path given on the command line:

    .venv/bin/python -m bench.check_kinematics DATA_FOLDER   # e.g. the shared data folder
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from analysis.bvh import read
from analysis.kinematics import forward_kinematics as kin
from tests.analysis.test_kinematics import TOL, reference_of


def bvh_files(root: Path) -> list[Path]:
    return sorted(p for p in root.rglob("*") if p.name.endswith((".bvh", ".bvh.gz")))


def worst_error(path: Path) -> float:
    motion = read(path)
    return float(np.abs(kin.positions(motion) - reference_of(motion).pos).max(initial=0.0))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("root", type=Path, help="folder searched recursively for .bvh/.bvh.gz")
    args = parser.parse_args()
    files = bvh_files(args.root)
    errors = {path: worst_error(path) for path in files}
    failed = [p for p, e in errors.items() if e > TOL]
    for path in failed:
        print(f"FAIL {path}: {errors[path]:.3g}")
    worst = max(errors.values(), default=0.0)
    print(
        f"{len(files)} files, worst |ours - reference| = {worst:.3g} file units, "
        f"{len(failed)} over {TOL}"
    )
    return 1 if failed or not files else 0


if __name__ == "__main__":
    sys.exit(main())
