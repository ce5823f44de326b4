"""Whether a change to the analysis leaves its results unchanged, bit for bit.

``--snapshot DIR`` analyses every development session (the 140 UI-PRMD sessions of
``data/ui-prmd/sessions``, each against its exercise's s01-correct tutor, cold-start models) and
the 60 s × 120 fps × 31-joint recording of `bench.bench_pipeline` (against its 120 fps tutor's
model), and stores each result's JSON (without the stage times) and playback arrays, and each
model's fitted parts, in DIR. ``--compare DIR`` does the same again and lists every session,
field or array that differs from the stored one (floats compared by their bits; NaN equals NaN).

    python -m bench.compare_results --snapshot /tmp/before
    python -m bench.compare_results --compare /tmp/before
"""

from __future__ import annotations

import argparse
import hashlib
import pickle
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion, read
from analysis.kinematics import resample
from analysis.pipeline import FittedModel, analyse, build_model
from bench.bench_pipeline import landmarks, with_extra_joints

Arrays = dict[str, npt.NDArray[Any]]
Outcome = tuple[dict[str, Any], Arrays]


def model_state(model: FittedModel) -> dict[str, str]:
    """The model's fitted parts (what the analysis reads of it, the tutor included) as
    {path: value}: arrays by their type, shape and a digest of their bytes, floats by their bits,
    sets sorted (a pickle's bytes change with the string hashes of each process)."""
    out: dict[str, str] = {}
    _flatten(model, "model", out, set())
    return out


def _flatten(value: Any, path: str, out: dict[str, str], seen: set[int]) -> None:  # noqa: C901, PLR0912
    if value is None or isinstance(value, (bool, int, str, bytes)):
        out[path] = repr(value)
        return
    if isinstance(value, float):
        out[path] = value.hex()
        return
    if isinstance(value, (np.ndarray, np.generic)):
        array = np.asarray(value)
        if array.dtype.kind == "O":
            _flatten(array.tolist(), path, out, seen)
        else:
            digest = hashlib.sha256(np.ascontiguousarray(array).tobytes()).hexdigest()
            out[path] = f"{array.dtype.str}{array.shape} {digest}"
        return
    if id(value) in seen:  # shared or cyclic: compared where first met
        out[path] = "(seen)"
        return
    seen.add(id(value))
    if isinstance(value, (list, tuple)):
        for k, item in enumerate(value):
            _flatten(item, f"{path}[{k}]", out, seen)
    elif isinstance(value, (set, frozenset)):
        out[path] = repr(sorted(repr(v) for v in value))
    elif isinstance(value, dict):
        for key, item in value.items():
            _flatten(item, f"{path}[{key!r}]", out, seen)
    elif callable(value) and not hasattr(value, "__dict__"):
        out[path] = getattr(value, "__qualname__", repr(value))
    else:
        state = value.__getstate__() if hasattr(value, "__getstate__") else vars(value)
        out[f"{path}:type"] = type(value).__qualname__
        _flatten(state, path, out, seen)


def outcome(motion: Motion, model: FittedModel) -> Outcome:
    result = analyse(motion, model)
    summary = result.to_json()
    summary.pop("timings_ms")
    return summary, result.arrays()


def long_recording(data: Path) -> Iterator[tuple[str, str, FittedModel, Motion]]:
    """The benchmark's 60 s × 120 fps × 31-joint recording and its tutor's model."""
    tutor_name = "sessions/m01_s01_correct.bvh.gz"
    frames, types = landmarks(data, tutor_name)
    tutor = with_extra_joints(resample(read(data / tutor_name), 120.0))
    model = build_model(tutor, [min(4 * f, tutor.n_frames - 1) for f in frames], types)
    take = resample(read(data / "sessions/m01_s03_correct.bvh.gz"), 120.0)
    repeats = int(np.ceil(7200 / take.n_frames))
    recording = with_extra_joints(take.with_frames(np.tile(take.frames, (repeats, 1))[:7200]))
    yield "long recording (60 s, 120 fps, 31 joints)", "120 fps tutor", model, recording


def sessions(data: Path) -> Iterator[tuple[str, str, FittedModel, Motion]]:
    models: dict[str, FittedModel] = {}
    for path in sorted((data / "sessions").glob("*.bvh.gz")):
        exercise = path.name[:3]
        if exercise not in models:
            name = f"sessions/{exercise}_s01_correct.bvh.gz"
            models[exercise] = build_model(read(data / name), *landmarks(data, name))
        yield path.name, exercise, models[exercise], read(path)


def collect(data: Path) -> tuple[dict[str, Outcome], dict[str, dict[str, str]]]:
    results: dict[str, Outcome] = {}
    models: dict[str, dict[str, str]] = {}
    for source in (long_recording(data), sessions(data)):
        for name, tutor, model, motion in source:
            if f"model of {tutor}" not in models:  # as built, before any analysis used it
                models[f"model of {tutor}"] = model_state(model)
            results[name] = outcome(motion, model)
            print(".", end="", flush=True)
    print()
    return results, models


def json_differences(before: Any, after: Any, where: str = "") -> list[str]:
    """Paths where two JSON values differ (a float by its bits, so 0.1 + 0.2 ≠ 0.3)."""
    if isinstance(before, dict) and isinstance(after, dict):
        out = [f"{where}.{k}: only one side" for k in before.keys() ^ after.keys()]
        for key in before.keys() & after.keys():
            out += json_differences(before[key], after[key], f"{where}.{key}")
        return out
    if isinstance(before, list) and isinstance(after, list):
        if len(before) != len(after):
            return [f"{where}: {len(before)} items → {len(after)}"]
        return [d for k, (a, b) in enumerate(zip(before, after, strict=True)) for d in
                json_differences(a, b, f"{where}[{k}]")]  # fmt: skip
    if type(before) is not type(after) or repr(before) != repr(after):
        return [f"{where}: {before!r} → {after!r}"]
    return []


def array_differences(before: Arrays, after: Arrays) -> list[str]:
    out = [f"array {k}: only one side" for k in before.keys() ^ after.keys()]
    for key in sorted(before.keys() & after.keys()):
        a, b = before[key], after[key]
        if a.dtype != b.dtype or a.shape != b.shape:
            out.append(f"array {key}: {a.dtype}{a.shape} → {b.dtype}{b.shape}")
        elif a.tobytes() != b.tobytes():
            differ = (
                int(np.count_nonzero(a != b))
                if a.dtype.kind != "f"
                else int(np.count_nonzero(~((a == b) | (np.isnan(a) & np.isnan(b)))))
            )
            largest = float(np.nanmax(np.abs(a - b))) if a.dtype.kind == "f" else float("nan")
            out.append(f"array {key}: {differ} values differ (largest by {largest:.3g})")
    return out


def compare(stored: Path, data: Path) -> int:
    with open(stored / "results.pickle", "rb") as handle:
        before, before_models = pickle.load(handle)
    after, after_models = collect(data)
    problems = [
        f"{name}: {line}"
        for name, state in sorted(before_models.items())
        for line in json_differences(state, after_models.get(name, {}))
    ]
    problems += [f"{name}: only one side" for name in before.keys() ^ after.keys()]
    for name in sorted(before.keys() & after.keys()):
        (json_a, arrays_a), (json_b, arrays_b) = before[name], after[name]
        for line in json_differences(json_a, json_b) + array_differences(arrays_a, arrays_b):
            problems.append(f"{name}: {line}")
    for line in problems:
        print(line)
    print(f"{len(after)} results and {len(after_models)} models compared: "
          f"{len(problems)} differences")  # fmt: skip
    return 1 if problems else 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=Path("data/ui-prmd"))
    action = parser.add_mutually_exclusive_group(required=True)
    action.add_argument("--snapshot", type=Path, help="store the results in this folder")
    action.add_argument("--compare", type=Path, help="compare with the results stored here")
    args = parser.parse_args()
    if args.compare is not None:
        sys.exit(compare(args.compare, args.data))
    args.snapshot.mkdir(parents=True, exist_ok=True)
    with open(args.snapshot / "results.pickle", "wb") as handle:
        pickle.dump(collect(args.data), handle, protocol=pickle.HIGHEST_PROTOCOL)
    print(f"stored in {args.snapshot}")


if __name__ == "__main__":
    main()
