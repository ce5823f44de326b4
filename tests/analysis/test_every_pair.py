"""Every (recording, model) pair of the repository's test data ends in a result or a plain reason.

`python -m analysis analyse` (the CLI's ``main``) runs in a forked child per pair, under a 3 GiB
address-space limit and 60 s, on the UI-PRMD single repetitions of all ten exercises, a few whole
sessions and the other rigs' files (data/rigs), against models built once per session from the
tutors of all ten exercises (`bench/eval_mismatch.py` runs all 140 development sessions against
the ten models: too long for the suite). Each answer must be a result (exit
0, one JSON object with ``match``; a recording that does not fit has no repetition and a null
score) or exit 2 with one line on stderr; a traceback (an exception that reached the user
without a reason) fails the test (issue 25).
"""

from __future__ import annotations

import json
import os
import resource
import signal
import sys
import time
import traceback
from pathlib import Path

import pytest

from analysis.__main__ import main

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data" / "ui-prmd"
MODEL_EXERCISES = tuple(f"m{k:02d}" for k in range(1, 11))  # all ten
LIMIT_BYTES = 3 * 1024**3
SECONDS = 60
PARALLEL = 2


SESSIONS = ("m01_s02_correct", "m05_s04_incorrect", "m07_s03_incorrect", "m10_s06_correct")


def recordings() -> list[Path]:
    reps = sorted(DATA.glob("reps/m*_s01_e02.bvh.gz"))
    reps += sorted(DATA.glob("reps/m0[1357]_*_e01_inc*"))
    sessions = [DATA / f"sessions/{name}.bvh.gz" for name in SESSIONS]
    return reps + sessions + sorted((ROOT / "data" / "rigs").glob("*.bvh"))


def tutor_marks(exercise: str) -> tuple[str, str]:
    for line in (DATA / "landmarks.csv").read_text().splitlines():
        if line.startswith(f"sessions/{exercise}_s01_correct"):
            _, frames, types = line.split(",")
            return frames, types
    raise LookupError(exercise)


@pytest.fixture(scope="session")
def models(tmp_path_factory) -> dict[str, Path]:
    """One cold-start model per exercise, built once per test session."""
    folder = tmp_path_factory.mktemp("pair-models")
    out = {}
    for exercise in MODEL_EXERCISES:
        frames, types = tutor_marks(exercise)
        out[exercise] = folder / f"{exercise}.model"
        tutor = DATA / f"sessions/{exercise}_s01_correct.bvh.gz"
        argv = ["build-model", "--tutor", str(tutor), "--landmarks", frames, "--types", types,
                "--out", str(out[exercise])]  # fmt: skip
        assert main(argv) == 0
    return out


def child(argv: list[str], out: Path, err: Path) -> None:
    """In the forked child: limits, stdout/stderr to files, the CLI, exit with its code (1 and
    a traceback on stderr for an exception that escapes, as the interpreter would)."""
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT_BYTES, LIMIT_BYTES))
    signal.alarm(SECONDS)  # the default action ends the child: seen as a signal, not an exit
    code = 1
    with open(out, "w") as stdout, open(err, "w") as stderr:
        sys.stdout, sys.stderr = stdout, stderr
        try:
            code = main(argv)
        except SystemExit as stop:
            code = stop.code if isinstance(stop.code, int) else 1
        except BaseException:
            traceback.print_exc()
        stdout.flush()
        stderr.flush()
    os._exit(code)


def run_all(jobs: list[tuple[str, list[str]]], folder: Path) -> dict[str, tuple[int, str, str]]:
    """Every job in its own forked child, `PARALLEL` at a time: {label: (status, out, err)}."""
    pending, running, done = list(jobs), {}, {}
    while pending or running:
        while pending and len(running) < PARALLEL:
            label, argv = pending.pop()
            out = folder / f"{len(pending)}.out"
            err = out.with_suffix(".err")
            pid = os.fork()
            if pid == 0:
                child(argv, out, err)
            running[pid] = (label, out, err)
        pid, status = os.wait()
        label, out, err = running.pop(pid)
        done[label] = (status, out.read_text(), err.read_text())
    return done


def check_answer(label: str, status: int, out: str, err: str) -> str:
    """'fits', 'does not fit' or 'refused'; fails the test on anything else."""
    assert os.WIFEXITED(status), f"{label}: ended by signal {os.WTERMSIG(status)} ({err[-300:]})"
    code = os.WEXITSTATUS(status)
    assert "Traceback" not in err, f"{label}: traceback\n{err}"
    if code == 2:
        assert out == "" and err.startswith("error: ") and len(err.strip().splitlines()) == 1, (
            label,
            err,
        )
        return "refused"
    assert code == 0, f"{label}: exit {code}\n{err}"
    result = json.loads(out)
    if result["match"]["fits"]:
        assert isinstance(result["score"], float), label
        return "fits"
    assert result["repetitions"] == [] and result["score"] is None, label
    assert result["match"]["message"].startswith("This recording does not look like"), label
    return "does not fit"


def test_every_recording_model_pair_ends_in_a_result_or_a_plain_reason(models, tmp_path):
    jobs = [
        (f"{path.name} / {exercise}",
         ["analyse", "--model", str(model), str(path), "--json"])
        for path in recordings() for exercise, model in models.items()
    ]  # fmt: skip
    start = time.perf_counter()
    answers = run_all(jobs, tmp_path)
    kinds = {label: check_answer(label, *answer) for label, answer in answers.items()}
    assert len(kinds) == len(jobs) >= 100
    # the right exercise is analysed; another exercise is not scored as a bad one
    for exercise in MODEL_EXERCISES:
        assert kinds[f"{exercise}_s01_e02.bvh.gz / {exercise}"] == "fits"
    assert kinds["m07_s01_e02.bvh.gz / m01"] == "does not fit"
    assert kinds["m01_s01_e02.bvh.gz / m07"] == "does not fit"
    assert kinds["fairmotion_sinusoidal.bvh / m01"] == "refused"  # no human skeleton
    assert time.perf_counter() - start < 240


def test_an_exercise_without_key_poses_is_refused_with_a_plain_reason(tmp_path, capsys):
    tutor = DATA / "sessions/m07_s01_correct.bvh.gz"
    argv = ["build-model", "--tutor", str(tutor), "--landmarks", "10", "--types", "1",
            "--out", str(tmp_path / "m")]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "cannot analyse recordings yet" in err and "trying again before that cannot help" in err
