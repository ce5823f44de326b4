"""Issue 34 item 6: ``python -m analysis`` works without the live client's network packages;
the capture client has its own entry point (``python -m capture``), which ``stream`` hands over
to. Each run is a fresh interpreter in which importing websockets (or any HTTP or web package)
fails, as on a machine that never installed them."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data" / "ui-prmd"
TUTOR = "sessions/m07_s01_correct.bvh.gz"
BLOCKED = ("websockets", "aiohttp", "httpx", "requests", "urllib3", "django", "celery", "capture")
# Runs the command line with the blocked packages unimportable, then says which got imported.
RUNNER = f"""
import json, sys
for name in {BLOCKED!r}:
    sys.modules[name] = None  # `import name` now raises ImportError
from analysis.__main__ import main
code = main(sys.argv[1:])
loaded = sorted(n for n in sys.modules if n.split(".")[0] in {BLOCKED!r} and sys.modules[n])
print(json.dumps({{"code": code, "loaded": loaded}}), file=sys.stderr)
"""


def landmarks(relative: str) -> tuple[str, str]:
    for line in (DATA / "landmarks.csv").read_text().splitlines():
        if line.startswith(relative):
            _, frames, types = line.split(",")
            return frames, types
    raise LookupError(relative)


def python(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, *args], check=False, cwd=ROOT, capture_output=True, text=True,
        timeout=120,
    )  # fmt: skip


def run(*args: str) -> tuple[subprocess.CompletedProcess, dict]:
    done = python("-c", RUNNER, *args)
    return done, json.loads(done.stderr.strip().splitlines()[-1])


def test_help_build_model_and_analyse_without_network_packages(tmp_path):
    helped = python("-c", RUNNER, "--help")  # argparse's --help exits 0 inside `main`
    assert helped.returncode == 0 and "build-model" in helped.stdout and "stream" in helped.stdout
    model = tmp_path / "m07.model"
    frames, types = landmarks(TUTOR)
    done, told = run(
        "build-model", "--tutor", str(DATA / TUTOR), "--landmarks", frames, "--types", types,
        "--out", str(model),
    )  # fmt: skip
    assert told == {"code": 0, "loaded": []}, done.stderr[-500:]
    session = DATA / "sessions/m07_s02_correct.bvh.gz"
    done, told = run("analyse", "--model", str(model), str(session), "--json")
    assert told == {"code": 0, "loaded": []}, done.stderr[-500:]
    result = json.loads(done.stdout)
    assert result["repetitions"] and result["match"]["fits"] is True


def test_stream_is_the_capture_clients_own_command():
    """Without the network packages, ``stream`` says what is missing; ``python -m capture``
    is the same command line."""
    done = python("-c", RUNNER, "stream", "--help")
    assert done.returncode != 0 and "capture" in done.stderr  # the hand-over, refused here
    own = python("-m", "capture", "--help")
    assert own.returncode == 0 and "--server" in own.stdout and "python -m capture" in own.stdout
