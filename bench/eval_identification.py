"""Exercise identification on UI-PRMD: 2-bit LUT-DTW (paper 002) against plain DTW.

Protocol (as in Takahara et al., section 4.2, with subjects as folds): every session of one subject
(10 exercises × correct/incorrect = 20 queries) is identified by its nearest neighbour among the
sessions of the other 6 subjects (120 references); 7 folds, 140 queries. Both methods see the same
17 body-part distance features resampled to the same frame rate and run the same compiled DTW
dynamic programme; only the frame-distance source differs (table lookup of 2-bit PCA codes vs
Euclidean distance of the continuous features).

    .venv/bin/python -m bench.eval_identification [--data data/ui-prmd] [--fps 15] [--sweep]
"""

from __future__ import annotations

import argparse
import csv
import os
import platform
import time
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from analysis.bvh import read
from analysis.kinematics import positions
from analysis.retrieval import recording_features
from analysis.retrieval.quantised import Metric, MotionRetriever, _fill_euclidean, _fill_lut

EXERCISES = {
    "m01": "deep squat",
    "m02": "hurdle step",
    "m03": "inline lunge",
    "m04": "side lunge",
    "m05": "sit to stand",
    "m06": "straight-leg raise",
    "m07": "shoulder abduction",
    "m08": "shoulder extension",
    "m09": "shoulder int./ext. rotation",
    "m10": "shoulder scaption",
}


@dataclass(frozen=True)
class Session:
    features: np.ndarray  # (F, 17)
    exercise: str
    subject: str


@dataclass(frozen=True)
class Outcome:
    predicted: list[str]
    truth: list[str]
    retrieval_s: float  # identify() over all queries (codes + DTW to every reference)
    fit_s: float  # PCA, thresholds, codes and (LUT) table build, all folds
    cells: int  # DTW cells evaluated

    @property
    def accuracy(self) -> float:
        return float(np.mean([p == t for p, t in zip(self.predicted, self.truth, strict=True)]))


def load_sessions(root: Path, fps: float) -> list[Session]:
    """Every session file listed in labels.csv, as features at `fps`."""
    sessions = []
    with (root / "labels.csv").open(newline="") as handle:
        for row in csv.DictReader(handle):
            if row["kind"] != "session":
                continue
            motion = read(root / row["file"])
            feats = recording_features(
                positions(motion), motion.skeleton.names, motion.fps, target_fps=fps
            )
            sessions.append(Session(feats, row["exercise"], row["subject"]))
    return sessions


def run(sessions: list[Session], metric: Metric, n_components: int = 6, repeat: int = 1) -> Outcome:
    """Leave-one-subject-out nearest-neighbour identification with one metric.

    Times are process CPU seconds (the VM is shared, so wall time counts other people's jobs),
    the best of `repeat` runs per fold.
    """
    predicted, truth, retrieval, fitting, cells = [], [], 0.0, 0.0, 0
    for subject in sorted({s.subject for s in sessions}):
        refs = [s for s in sessions if s.subject != subject]
        queries = [s for s in sessions if s.subject == subject]
        start = time.process_time()
        model = MotionRetriever(n_components=n_components, metric=metric)
        model.fit([s.features for s in refs], [s.exercise for s in refs])
        if metric == "lut":
            model.lut_  # noqa: B018 (build the table inside the fit time, not the retrieval time)
        fitting += time.process_time() - start
        best = np.inf
        for _ in range(repeat):
            start = time.process_time()
            guesses = [model.identify(q.features) for q in queries]
            best = min(best, time.process_time() - start)
        retrieval += best
        predicted += guesses
        truth += [q.exercise for q in queries]
        cells += sum(len(q.features) for q in queries) * int(model.offsets_[-1])
    return Outcome(predicted, truth, retrieval, fitting, cells)


@numba.njit(cache=True)
def _fill_only_lut(a: np.ndarray, b: np.ndarray, lut: np.ndarray) -> float:
    out = np.empty(b.shape[0])
    total = 0.0
    for i in range(a.shape[0]):
        _fill_lut(a[i], b, lut, out)
        total += out[i % b.shape[0]]
    return total


@numba.njit(cache=True)
def _fill_only_features(a: np.ndarray, bt: np.ndarray) -> float:
    out = np.empty(bt.shape[1])
    total = 0.0
    for i in range(a.shape[0]):
        _fill_euclidean(a[i], bt, out)
        total += out[i % bt.shape[1]]
    return total


def frame_distance_times(sessions: list[Session], repeat: int) -> tuple[float, float]:
    """CPU seconds for the frame distances alone (DTW step 1) of one fold's pairs."""
    refs = [s for s in sessions if s.subject != "s01"]
    queries = [s for s in sessions if s.subject == "s01"]
    model = MotionRetriever().fit([s.features for s in refs], [s.exercise for s in refs])
    lut = model.lut_
    codes = [model.codes(s.features) for s in sessions]
    by_id = {id(s): c for s, c in zip(sessions, codes, strict=True)}
    transposed = {id(r): np.ascontiguousarray(r.features.T) for r in refs}
    lut_s = dtw_s = np.inf
    for _ in range(repeat):
        start = time.process_time()
        for q in queries:
            for r in refs:
                _fill_only_lut(by_id[id(q)], by_id[id(r)], lut)
        lut_s = min(lut_s, time.process_time() - start)
        start = time.process_time()
        for q in queries:
            for r in refs:
                _fill_only_features(q.features, transposed[id(r)])
        dtw_s = min(dtw_s, time.process_time() - start)
    return lut_s, dtw_s


def warm_up() -> None:
    """Compile the numba kernels before any timing."""
    rng = np.random.default_rng(0)
    feats = [rng.normal(size=(20, 17)) for _ in range(4)]
    metrics: tuple[Metric, ...] = ("lut", "features")
    for metric in metrics:
        model = MotionRetriever(n_components=2, metric=metric).fit(feats, list("abab"))
        model.identify(feats[0])
    _fill_only_lut(np.zeros(3, np.int64), np.zeros(3, np.int64), np.zeros((4, 4), np.float32))
    _fill_only_features(feats[0], np.ascontiguousarray(feats[1].T))


def machine() -> str:
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine()


def print_main_table(lut: Outcome, dtw: Outcome) -> None:
    print("| method | accuracy | correct / queries | retrieval CPU time (s) | per query (ms) | "
          "ns per DTW cell | fit + table (s) |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for name, o in (("LUT-DTW (2-bit PCA codes, n = 6)", lut), ("plain DTW (17-D features)", dtw)):
        correct = sum(p == t for p, t in zip(o.predicted, o.truth, strict=True))
        print(
            f"| {name} | {100 * o.accuracy:.1f} % | {correct} / {len(o.truth)} | "
            f"{o.retrieval_s:.2f} | {1000 * o.retrieval_s / len(o.truth):.1f} | "
            f"{1e9 * o.retrieval_s / o.cells:.2f} | {o.fit_s:.2f} |"
        )
    print(f"\nSpeed-up of LUT-DTW over plain DTW (retrieval time): "
          f"{dtw.retrieval_s / lut.retrieval_s:.1f}×; accuracy difference "
          f"{100 * (lut.accuracy - dtw.accuracy):+.1f} points.")  # fmt: skip


def print_per_exercise(lut: Outcome, dtw: Outcome) -> None:
    print("\n| exercise | LUT-DTW correct / 14 | plain DTW correct / 14 | LUT-DTW mistaken for |")
    print("|---|---|---|---|")
    for code, name in EXERCISES.items():
        hits = [sum(p == t for p, t in zip(o.predicted, o.truth, strict=True) if t == code)
                for o in (lut, dtw)]  # fmt: skip
        wrong = sorted({p for p, t in zip(lut.predicted, lut.truth, strict=True)
                        if t == code and p != code})  # fmt: skip
        print(f"| {code} {name} | {hits[0]} | {hits[1]} | {', '.join(wrong) or '–'} |")


def sweep(sessions: list[Session]) -> None:
    """The paper's preliminary experiment (figs 3–5): accuracy and time against n."""
    print(
        "\n| n PCs | table entries | LUT-DTW accuracy | retrieval CPU time (s) | cumulative c_i |"
    )
    print("|---|---|---|---|---|")
    for n in range(1, 7):
        out = run(sessions, "lut", n)
        ratio = MotionRetriever(n_components=n).fit(
            [s.features for s in sessions], ["x"] * len(sessions)
        )
        print(f"| {n} | {4**n}² | {100 * out.accuracy:.1f} % | {out.retrieval_s:.2f} | "
              f"{ratio.explained_variance_ratio_.sum():.3f} |")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=Path("data/ui-prmd"))
    parser.add_argument("--fps", type=float, default=15.0, help="frame rate both methods use")
    parser.add_argument("--sweep", action="store_true", help="also vary n = 1..6 (paper 4.1)")
    parser.add_argument("--repeat", type=int, default=3, help="timing: best of this many runs")
    args = parser.parse_args()
    print(
        f"Date: {time.strftime('%Y-%m-%d')}; machine: {machine()} ({os.cpu_count()} cores), "
        f"single-threaded kernels; numba {numba.__version__}, numpy {np.__version__}"
    )
    start = time.perf_counter()
    sessions = load_sessions(args.data, args.fps)
    frames = [len(s.features) for s in sessions]
    print(f"{len(sessions)} sessions, {len({s.subject for s in sessions})} subjects, features at "
          f"{args.fps:g} fps: {min(frames)}–{max(frames)} frames (mean {np.mean(frames):.0f}); "
          f"loading took {time.perf_counter() - start:.1f} s\n")  # fmt: skip
    warm_up()
    lut = run(sessions, "lut", repeat=args.repeat)
    dtw = run(sessions, "features", repeat=args.repeat)
    print_main_table(lut, dtw)
    print_per_exercise(lut, dtw)
    lut_fill, dtw_fill = frame_distance_times(sessions, args.repeat)
    print(
        f"\nFrame distances alone (DTW step 1, one fold: 20 × 120 pairs): table lookup "
        f"{lut_fill:.2f} s, Euclidean {dtw_fill:.2f} s ({dtw_fill / lut_fill:.1f}× faster)."
    )
    if args.sweep:
        sweep(sessions)


if __name__ == "__main__":
    main()
