"""The options `uv pip install` needs to install what pip would on this machine, one a line.

uv reads no pip configuration (pip.conf, PIP_* variables), so a machine whose pip looks in extra
indexes or local wheel folders, or caps versions with a constraints file, would otherwise get
other sources, and maybe other versions, from uv. This reads pip's own answer
(`python -m pip config list`, run by the interpreter that runs this file) and prints the same
settings as uv's options. pip takes the highest version found in any index; so does uv with
``--index-strategy unsafe-best-match`` (its default stops at the first index naming the package).

Used by the Makefile: ``mapfile -t options < <(python3 deploy/uv_options.py)``.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterable, Mapping

# pip's setting -> uv's option; each of pip's values (space-separated in its configuration) is
# one option of uv's.
OPTIONS = {
    "index-url": "--index-url",
    "extra-index-url": "--extra-index-url",
    "find-links": "--find-links",
    "constraint": "--constraint",
}
# Where pip reads a setting for `pip install`, the one that wins first: its PIP_* variables, then
# its files' [install] section, then their [global] one.
SECTIONS = (":env:", "install", "global")


def pip_settings(lines: Iterable[str]) -> dict[str, str]:
    """``pip config list`` lines (``section.name='value'``) as {section.name: value}."""
    settings = {}
    for line in lines:
        key, sep, value = line.strip().partition("=")
        if sep:
            settings[key] = value.strip().strip("'\"")
    return settings


def setting(settings: Mapping[str, str], name: str) -> str:
    """pip's value of ``name`` for `pip install` ("" when unset)."""
    return next((settings[f"{s}.{name}"] for s in SECTIONS if f"{s}.{name}" in settings), "")


def uv_options(settings: Mapping[str, str]) -> list[str]:
    options = ["--index-strategy", "unsafe-best-match"]
    for name, option in OPTIONS.items():
        for value in setting(settings, name).split():
            options += [option, value]
    if setting(settings, "no-index").lower() in {"1", "true", "yes", "on"}:
        options.append("--no-index")
    return options


def main() -> int:
    listed = subprocess.run(
        [sys.executable, "-m", "pip", "config", "list"], capture_output=True, text=True, check=True
    )
    print("\n".join(uv_options(pip_settings(listed.stdout.splitlines()))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
