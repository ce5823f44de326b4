"""deploy/uv_options.py: uv gets the sources and caps pip has on this machine (uv reads no pip
configuration), so `make deps` installs what pip would."""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "deploy" / "uv_options.py"


def options_under(tmp_path: Path, config: str, **env: str) -> list[str]:
    """The script's options when pip's only configuration is ``config`` and ``env``."""
    path = tmp_path / "pip.conf"
    path.write_text(config)
    clean = {k: v for k, v in os.environ.items() if not k.startswith("PIP_")}
    clean.update(PIP_CONFIG_FILE=str(path), HOME=str(tmp_path), XDG_CONFIG_DIRS=str(tmp_path))
    answer = subprocess.run(
        [sys.executable, str(SCRIPT)], env={**clean, **env}, capture_output=True, text=True,
        check=True,
    )  # fmt: skip
    return answer.stdout.splitlines()


def pairs(options: list[str]) -> list[tuple[str, str]]:
    return [(a, b) for a, b in itertools.pairwise(options) if a.startswith("--")]


def test_indexes_wheel_folders_and_constraints_are_handed_to_uv(tmp_path):
    config = (
        "[global]\nextra-index-url = file:///srv/a/simple file:///srv/b/simple\n"
        "find-links = /srv/wheels\nconstraint = /srv/caps.txt\n"
    )
    found = pairs(options_under(tmp_path, config))
    assert ("--index-strategy", "unsafe-best-match") in found, "pip's best version of any index"
    assert ("--extra-index-url", "file:///srv/a/simple") in found
    assert ("--extra-index-url", "file:///srv/b/simple") in found
    assert ("--find-links", "/srv/wheels") in found
    assert ("--constraint", "/srv/caps.txt") in found


def test_pip_variables_win_over_its_files_and_install_over_global(tmp_path):
    config = "[global]\nfind-links = /srv/old\nindex-url = https://a/simple\n"
    config += "[install]\nindex-url = https://b/simple\n"
    found = pairs(options_under(tmp_path, config, PIP_FIND_LINKS="/srv/new"))
    assert ("--find-links", "/srv/new") in found and ("--find-links", "/srv/old") not in found
    assert ("--index-url", "https://b/simple") in found
    assert ("--index-url", "https://a/simple") not in found


def test_without_pip_settings_uv_keeps_its_own_defaults(tmp_path):
    assert options_under(tmp_path, "") == ["--index-strategy", "unsafe-best-match"]
