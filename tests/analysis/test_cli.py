"""``python -m analysis build-model | analyse`` per the interface contract: JSON out, exit 2 on bad
input."""

from __future__ import annotations

import gzip
import json
import subprocess
import sys
from pathlib import Path

import pytest

from analysis.__main__ import main

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data" / "ui-prmd"
TUTOR = DATA / "sessions/m07_s01_correct.bvh.gz"


def tutor_marks() -> tuple[str, str]:
    for line in (DATA / "landmarks.csv").read_text().splitlines():
        if line.startswith("sessions/m07_s01_correct"):
            _, frames, types = line.split(",")
            return frames, types
    raise LookupError


@pytest.fixture(scope="module")
def model_path(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("model") / "m07.model"
    frames, types = tutor_marks()
    train = f"{DATA / 'sessions/m07_s02_incorrect.bvh.gz'}|0;40;80|1;2;1|incorrect"
    code = main(["build-model", "--tutor", str(TUTOR), "--landmarks", frames, "--types", types,
                 "--train", train, "--out", str(out)])  # fmt: skip
    assert code == 0
    return out


def test_analyse_prints_the_contract_json(model_path, capsys):
    capsys.readouterr()
    recording = DATA / "sessions/m07_s03_correct.bvh.gz"
    code = main(["analyse", "--model", str(model_path), str(recording), "--json"])
    assert code == 0
    result = json.loads(capsys.readouterr().out)
    assert {"frames", "fps", "landmarks", "repetitions", "score", "assessment", "feedback",
            "timings_ms"} <= set(result)  # fmt: skip


def bad_inputs(tmp_path: Path) -> dict[str, Path]:
    text = gzip.decompress((DATA / "reps/m07_s01_e01.bvh.gz").read_bytes()).decode()
    truncated = tmp_path / "truncated.bvh"
    truncated.write_text(text[: len(text) // 2])
    other_rig = tmp_path / "other.bvh"
    other_rig.write_text(text.replace("Left", "Port").replace("Right", "Starboard"))
    header, motion = text.split("MOTION")
    lines = motion.strip().splitlines()
    three = tmp_path / "three.bvh"
    three.write_text(header + "MOTION\nFrames: 3\n" + "\n".join(lines[1:5]) + "\n")
    return {"truncated": truncated, "other rig": other_rig, "3 frames": three}


def test_bad_inputs_exit_2_with_one_line(model_path, tmp_path):
    for label, path in bad_inputs(tmp_path).items():
        run = subprocess.run(
            [sys.executable, "-m", "analysis", "analyse", "--model", str(model_path), str(path),
             "--json"],
            capture_output=True, text=True, cwd=ROOT, timeout=120, check=False,
        )  # fmt: skip
        assert run.returncode == 2, (label, run.stderr)
        assert run.stdout == ""
        assert len(run.stderr.strip().splitlines()) == 1 and run.stderr.startswith("error: ")


def test_bad_build_arguments_exit_2(tmp_path, capsys):
    code = main(["build-model", "--tutor", str(TUTOR), "--landmarks", "0;x", "--types", "1;1",
                 "--out", str(tmp_path / "m")])  # fmt: skip
    assert code == 2
    assert "whole numbers" in capsys.readouterr().err


def test_an_absurd_frame_time_exits_2_with_the_plain_reason_before_resampling(
    model_path, tmp_path, capsys
):
    """Issue 25: ``Frame Time: 1000`` was accepted and resampled to millions of frames."""
    text = gzip.decompress((DATA / "reps/m07_s01_e01.bvh.gz").read_bytes()).decode()
    absurd = tmp_path / "absurd.bvh"
    absurd.write_text(text.replace("Frame Time: 0.033333", "Frame Time: 1000"))
    capsys.readouterr()
    assert main(["analyse", "--model", str(model_path), str(absurd), "--json"]) == 2
    out = capsys.readouterr()
    assert out.out == ""
    (line,) = out.err.strip().splitlines()
    assert line.startswith("error: The file says each frame lasts 1000 s")
    assert "Export the recording again" in line
