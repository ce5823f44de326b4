"""``python -m analysis build-model | analyse`` (README, "Command line"): JSON to stdout, exit 2
on bad input.

    python -m analysis build-model --tutor TUTOR.bvh[.gz] --landmarks "f1;f2;..." \\
        --types "t1;t2;..." [--train "REC.bvh.gz|f1;f2;...|t1;t2;...|LABEL" ...] --out MODEL
    python -m analysis analyse --model MODEL RECORDING.bvh[.gz] --json

Recordings and tutors may be any capture file `analysis.sources.read_recording` reads (.bvh,
.bvh.gz, Kinect .csv, Azure Kinect or MediaPipe .json, .trc, .c3d); the result names its source.
    python -m analysis stream ...   (live sessions: handed over to ``python -m capture``)

The top of the core: it may import every package of `analysis` and hands the `stream`
subcommand over to the capture client above the core. Importing it runs nothing; tests and
`tests/hostile_run.py` call `main(argv)` (and may replace `load_model`).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from analysis.bvh import AnalysisInputError, BVHError
from analysis.bvh.io import Motion
from analysis.landmarks import KeyPoses
from analysis.pipeline.match import Candidate, MatchContext, features_of
from analysis.pipeline.model import ModelVersionError, build_model, dump_model, load_model
from analysis.pipeline.model_fit import TrainingRecording
from analysis.pipeline.run import analyse
from analysis.sources import ImportedRecording, read_recording

LABELS = ("correct", "incorrect", "1", "2", "3", "4")


class UsageError(ValueError):
    """Arguments that cannot be used as given (reported in one line, exit 2)."""


def load(path: str) -> ImportedRecording:
    """Any capture file, by its name and content (`analysis.sources.read_recording`)."""
    return read_recording(str(path), Path(path).read_bytes())


def read(path: str) -> Motion:
    return load(path).motion


def _ints(text: str, what: str) -> list[int]:
    try:
        return [int(v) for v in text.replace(",", ";").split(";") if v.strip()]
    except ValueError:
        raise UsageError(f"{what} must be whole numbers separated by ';', got {text!r}") from None


def _training(spec: str) -> TrainingRecording:
    parts = spec.split("|")
    if len(parts) != 4:
        raise UsageError(f"--train takes 'FILE|frames|types|LABEL', got {spec!r}")
    path, frames, types, label = parts
    if label not in LABELS:
        raise UsageError(f"the label must be one of {', '.join(LABELS)}, got {label!r}")
    marked, typed = _ints(frames, "frames"), _ints(types, "types")
    if len(marked) != len(typed):
        raise UsageError(f"--train gives {len(marked)} key-pose frames but {len(typed)} types")
    key_poses = KeyPoses.of(marked, typed)
    return TrainingRecording(read(path), key_poses, label)


def build(args: argparse.Namespace) -> int:
    model = build_model(
        read(args.tutor),
        _ints(args.landmarks, "--landmarks"),
        _ints(args.types, "--types"),
        training=[_training(spec) for spec in args.train],
    )
    with open(args.out, "wb") as out:
        dump_model(model, out)
    print(json.dumps({"model": str(args.out), "report": model.report}))
    return 0


def _context(args: argparse.Namespace) -> MatchContext:
    """The exercise's name and the other exercises (``--other ID=MODEL``) for the fit check."""
    others = []
    for spec in args.other:
        name, sep, path = spec.partition("=")
        if not sep or not name or not path:
            raise UsageError(f"--other takes 'ID=MODEL', got {spec!r}")
        tutor = load_model(Path(path).read_bytes()).tutor
        others.append(Candidate(name, name, features_of(tutor)))
    return MatchContext(args.exercise_name, tuple(others))


def run_analysis(args: argparse.Namespace) -> int:
    model = load_model(Path(args.model).read_bytes())
    recording = load(args.recording)
    context = _context(args)
    result = analyse(recording.motion, model, match=context, lost_frames=recording.lost_frames)
    summary = dataclasses.replace(result.summary, source=recording.source)
    result = dataclasses.replace(result, summary=summary)
    print(json.dumps(result.to_json(), indent=2 if not args.json else None))
    return 0


def parser() -> argparse.ArgumentParser:
    top = argparse.ArgumentParser(prog="python -m analysis", description=__doc__.split("\n")[0])
    commands = top.add_subparsers(dest="command", required=True)
    b = commands.add_parser("build-model", help="fit an exercise model from a tutor recording")
    b.add_argument("--tutor", required=True)
    b.add_argument("--landmarks", required=True, help="tutor key-pose frames, 'f1;f2;...'")
    b.add_argument("--types", required=True, help="their landmark types, 't1;t2;...'")
    b.add_argument("--train", action="append", default=[], help="'FILE|frames|types|LABEL'")
    b.add_argument("--out", required=True)
    b.set_defaults(handler=build)
    a = commands.add_parser("analyse", help="analyse a recording against a model")
    a.add_argument("--model", required=True)
    a.add_argument("recording")
    a.add_argument("--json", action="store_true", help="one compact JSON object")
    a.add_argument("--exercise-name", default="this exercise", help="for 'does not look like'")
    a.add_argument(
        "--other", action="append", default=[], metavar="ID=MODEL",
        help="another exercise's model: a recording nearer its tutor is named by ID",
    )  # fmt: skip
    a.set_defaults(handler=run_analysis)
    # Listed for --help only: `main` hands `stream ...` to the capture client before parsing.
    commands.add_parser(
        "stream", help="stream a recording to an on-line aligner (python -m capture)"
    )
    return top


def hand_over_stream(argv: Sequence[str]) -> int:
    """``stream ...``: the capture client's own command line (``python -m capture``)."""
    # Imported here, only to stream: the capture client needs the network packages
    # (websockets), which `analyse` and `build-model` never do (not a cycle: capture imports
    # analysis.live and the model, never this module).
    from capture.stream import main as stream_main

    return stream_main(argv)


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["stream"]:
        return hand_over_stream(argv[1:])
    args = parser().parse_args(argv)
    try:
        return int(args.handler(args))
    except (BVHError, AnalysisInputError, ModelVersionError, UsageError, OSError) as error:
        print(f"error: {_one_line(error)}", file=sys.stderr)
        return 2
    except ValueError as error:  # bad landmarks or options for build-model
        print(f"error: {_one_line(error)}", file=sys.stderr)
        return 2


def _one_line(error: Exception) -> str:
    return " ".join(str(error).split()) or type(error).__name__


if __name__ == "__main__":
    raise SystemExit(main())
