"""Run ``python -m analysis analyse`` on generated hostile files (`tests.hostile_bvh`), each in its
own process under a 3 GiB address-space limit and a 60 s limit, and sort every answer:

- ``result``: exit 0 and one JSON object on stdout;
- ``refused``: exit 2 and one line on stderr, ``error: ...``;
- anything else (a traceback, another exit status, a killed or timed-out process) is ``broken``.

To be fast, this process imports the analysis, loads the model once and runs one recording through
every stage (so nothing is compiled or loaded again), then forks a child per file that calls the
command line's ``main()``; the children inherit the loaded model (the command's ``load_model`` is
served from it). ``--count 100000`` is the long run (`make fuzz`), 10,000 is `make hostile`; the
suite runs 2,000 (`tests/analysis/test_hostile_files.py`). Prints one JSON summary line.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import resource
import signal
import sys
import tempfile
import time
import traceback
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

ADDRESS_SPACE = 3 << 30
TIME_LIMIT_S = 60.0
ROOT = Path(__file__).resolve().parents[1]
TUTOR = ROOT / "data/ui-prmd/sessions/m07_s01_correct.bvh.gz"


@dataclass
class Running:
    index: int
    family: str
    started: float
    out: Path
    err: Path


@dataclass
class Tally:
    outcomes: Counter[str] = field(default_factory=Counter)
    by_family: dict[str, Counter[str]] = field(default_factory=dict)
    broken: list[dict[str, object]] = field(default_factory=list)
    slowest_s: float = 0.0

    def add(self, run: Running, outcome: str, detail: str, seconds: float) -> None:
        self.outcomes[outcome] += 1
        self.by_family.setdefault(run.family, Counter())[outcome] += 1
        self.slowest_s = max(self.slowest_s, seconds)
        if outcome == "broken" and len(self.broken) < 20:
            self.broken.append({"case": run.index, "family": run.family, "detail": detail[-1500:]})


def tutor_marks() -> tuple[list[int], list[int]]:
    for line in (ROOT / "data/ui-prmd/landmarks.csv").read_text().splitlines():
        if line.startswith("sessions/m07_s01_correct"):
            _, frames, types = line.split(",")
            return [int(v) for v in frames.split(";")], [int(v) for v in types.split(";")]
    raise LookupError("no key poses for the tutor in data/ui-prmd/landmarks.csv")


def prepare_parent(model_path: Path | None) -> Path:
    """Import, build or load the model, warm every stage up; returns the model's path."""
    from analysis import __main__ as cli
    from analysis.bvh import read
    from analysis.pipeline.model import build_model, dump_model, load_model

    if model_path is None:
        model_path = Path(tempfile.mkdtemp(prefix="hostile-model-")) / "m07.model"
        with open(model_path, "wb") as out:
            dump_model(build_model(read(TUTOR), *tutor_marks()), out)
    model = load_model(model_path.read_bytes())
    cli.load_model = lambda _data: model  # type: ignore[assignment]  # children share the loaded one
    cli.parser()  # its lazy imports happen here, once
    warm_up(cli, model_path)
    return model_path


def warm_up(cli, model_path: Path) -> None:
    """One recording of the model's exercise, one of another and one of another rig through
    every stage, so the children find every compiled function already loaded."""
    devnull = open(os.devnull, "w")  # noqa: SIM115 (kept for the process)
    saved = sys.stdout, sys.stderr
    sys.stdout = sys.stderr = devnull
    try:
        for name in ("data/ui-prmd/reps/m07_s01_e01.bvh.gz", "data/ui-prmd/reps/m01_s01_e01.bvh.gz",
                     "data/rigs/AnimatedDrawings_cmu1_jumping_jacks.bvh"):  # fmt: skip
            cli.main(["analyse", "--model", str(model_path), str(ROOT / name), "--json"])
    finally:
        sys.stdout, sys.stderr = saved


def child(case: tuple[int, int, list[bytes]], model_path: Path, out: Path, err: Path) -> None:
    """In the forked process: build the case's file, limits, output to files, the command, then
    exit without cleanup. The parent only forks and waits: the less it touches between forks,
    the fewer pages each fork makes it copy."""
    from analysis import __main__ as cli
    from tests.hostile_bvh import hostile_case

    seed, index, bases = case
    path = out.with_suffix(".bvh")
    path.write_bytes(hostile_case(seed, index, bases)[1])
    argv = ["analyse", "--model", str(model_path), str(path), "--json"]
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))
    out_fd = os.open(out, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    err_fd = os.open(err, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    os.dup2(out_fd, 1)
    os.dup2(err_fd, 2)
    code = 1
    try:
        code = cli.main(argv)
    except SystemExit as done:
        code = done.code if isinstance(done.code, int) else 1
    except BaseException:  # exactly what the test looks for: it is printed and counted
        traceback.print_exc()
        code = 1
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def classify(code: int, out: str, err: str) -> tuple[str, str]:
    if code == 0:
        try:
            parsed = json.loads(out)
        except ValueError:
            return "broken", f"exit 0 without one JSON object: {out[:300]!r}"
        ok = isinstance(parsed, dict) and "frames" in parsed and not err.strip()
        return ("result", "") if ok else ("broken", f"exit 0 but: {out[:200]!r} {err[:300]!r}")
    lines = err.strip().splitlines()
    if code == 2 and len(lines) == 1 and lines[0].startswith("error: ") and not out:
        return "refused", lines[0]
    return "broken", f"exit {code}: {err}"


def finish(run: Running, status: int, tally: Tally) -> None:
    seconds = time.monotonic() - run.started
    out, err = run.out.read_text(errors="replace"), run.err.read_text(errors="replace")
    if os.WIFSIGNALED(status):
        outcome, detail = "broken", f"killed by signal {os.WTERMSIG(status)}: {err}"
    else:
        outcome, detail = classify(os.WEXITSTATUS(status), out, err)
    tally.add(run, outcome, detail, seconds)
    for path in (run.out, run.err, run.out.with_suffix(".bvh")):
        path.unlink(missing_ok=True)


def reap(running: dict[int, Running], tally: Tally, block: bool) -> None:
    """Collect finished children; kill any past the time limit."""
    now = time.monotonic()
    for pid, run in list(running.items()):
        if now - run.started > TIME_LIMIT_S:
            os.kill(pid, signal.SIGKILL)
    while running:
        pid, status = os.waitpid(-1, 0 if block else os.WNOHANG)
        if pid == 0:
            return
        run = running.pop(pid)
        finish(run, status, tally)
        block = False


def run_cases(model_path: Path, seed: int, count: int, jobs: int, folder: Path) -> Tally:
    from tests.hostile_bvh import base_texts, family_of

    tally, running = Tally(), {}
    bases = base_texts()
    gc.freeze()  # the collector then walks (and dirties) none of the pages the children share
    for index in range(count):
        while len(running) >= jobs:
            reap(running, tally, block=True)
        if index and index % 1000 == 0:  # for long runs (make fuzz): where it is, on stderr
            print(f"{index} cases: {dict(tally.outcomes)}", file=sys.stderr, flush=True)
        out, err = folder / f"{index}.out", folder / f"{index}.err"
        pid = os.fork()
        if pid == 0:
            child((seed, index, bases), model_path, out, err)
        running[pid] = Running(index, family_of(seed, index)[0], time.monotonic(), out, err)
    while running:
        reap(running, tally, block=True)
    return tally


def main(argv: list[str] | None = None) -> int:
    options = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    options.add_argument("--count", type=int, default=10_000)
    options.add_argument("--seed", type=int, default=25)
    options.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    options.add_argument("--model", type=Path, default=None, help="default: built from test data")
    args = options.parse_args(argv)
    started = time.monotonic()
    model_path = prepare_parent(args.model)
    ready = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="hostile-") as folder:
        tally = run_cases(model_path, args.seed, args.count, args.jobs, Path(folder))
    summary = {
        "count": args.count, "seed": args.seed, "outcomes": dict(tally.outcomes),
        "by_family": {k: dict(v) for k, v in sorted(tally.by_family.items())},
        "broken": tally.broken, "slowest_s": round(tally.slowest_s, 3),
        "setup_s": round(ready - started, 1), "run_s": round(time.monotonic() - ready, 1),
    }  # fmt: skip
    print(json.dumps(summary))
    return 0 if not tally.outcomes["broken"] else 1


if __name__ == "__main__":
    sys.exit(main())
