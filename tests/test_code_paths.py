"""Issue 34 item 6: the code says the truth about itself. Every file a docstring or comment of the
project's code cites (``docs/sections/clinical.md``, ``tests/webapp/conftest.py``) exists in the
repository, and every module it names (`analysis.pipeline.results`,
`webapp.api.result_schema.add_result_components`) resolves to a module of the repository and a
name that module defines, imports or re-exports."""

from __future__ import annotations

import io
import re
import tokenize
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("analysis", "capture", "workers", "webapp", "bench", "tests")
SKIPPED = ("migrations", "node_modules", ".venv", "fixtures")
# A cited file: a path with a folder (resolved from the repository's root), or a bare file name
# of these kinds (found anywhere in it).
FILE = re.compile(
    r"(?<![\w./-])((?:[\w-]+/)*[\w-]+\.(?:py|md|html|js|css|toml|cfg|ini|yml|yaml))\b"
)
MODULE = re.compile(rf"`((?:{'|'.join(PACKAGES)})(?:\.\w+)+)`")
IGNORED_FILES = {"__init__.py", "__main__.py", "conftest.py", "setup.py", "manage.py"}
# Names that are not files of the repository: libraries' names, a usage line's placeholder.
NOT_FILES = {"three.js", "plotly.js", "FILE.md"}


def code_files() -> list[Path]:
    return sorted(
        path
        for package in PACKAGES
        for path in (ROOT / package).rglob("*.py")
        if not any(part in SKIPPED for part in path.parts)
    )


# A string token right after these starts a statement: a docstring (or a bare string statement).
STATEMENT_STARTS = (
    tokenize.INDENT, tokenize.NEWLINE, tokenize.NL, tokenize.DEDENT, tokenize.ENCODING,
)  # fmt: skip


def prose(source: str) -> list[tuple[int, str]]:
    """(line, text) of each docstring and comment of a module."""
    found = []
    tokens = tokenize.generate_tokens(io.StringIO(source).readline)
    previous = tokenize.INDENT
    for token in tokens:
        docstring = token.type == tokenize.STRING and previous in STATEMENT_STARTS
        if token.type == tokenize.COMMENT or docstring:
            found.append((token.start[0], token.string))
        if token.type not in (tokenize.COMMENT, tokenize.NL):
            previous = token.type
    return found


def all_file_paths() -> set[str]:
    return {
        path.relative_to(ROOT).as_posix()
        for path in ROOT.rglob("*")
        if path.is_file() and not {".venv", "node_modules", ".git"} & set(path.parts)
    }


def file_exists(cited: str, paths: set[str]) -> bool:
    """A bare name anywhere in the repository; a path from its root or from a folder in it."""
    if cited in NOT_FILES or cited in IGNORED_FILES:
        return True
    return any(p == cited or p.endswith("/" + cited) for p in paths)


def defines(source: str, name: str) -> bool:
    pattern = rf"(^|\W)(def|class)\s+{name}\b|^\s*{name}\s*[:=]|import[^\n]*\b{name}\b|\"{name}\""
    return re.search(pattern, source, re.M) is not None


def module_resolves(dotted: str) -> bool:
    """`a.b.c.Name.attr`: the longest prefix that is a file or package of the repository, then
    at most two names, the first of which that module defines or imports."""
    parts = dotted.split(".")
    path = ROOT / parts[0]
    used = 1
    while used < len(parts):
        if (path / parts[used]).is_dir():
            path = path / parts[used]
        elif (path / f"{parts[used]}.py").is_file():
            path = path / f"{parts[used]}.py"
        else:
            break
        used += 1
    rest = parts[used:]
    if not rest:
        return True
    source_file = path / "__init__.py" if path.is_dir() else path
    if len(rest) > 2 or not source_file.is_file():
        return False
    return defines(source_file.read_text("utf-8"), rest[0])


def wrong_citations() -> list[str]:
    paths = all_file_paths()
    wrong = []
    for path in code_files():
        where = path.relative_to(ROOT)
        for line, text in prose(path.read_text("utf-8")):
            for cited in FILE.findall(text):
                if not file_exists(cited, paths):
                    wrong.append(f"{where}:{line}: file {cited}")
            for dotted in MODULE.findall(text):
                if not module_resolves(dotted):
                    wrong.append(f"{where}:{line}: module {dotted}")
    return wrong


def test_code_cites_files_and_modules_that_exist():
    wrong = wrong_citations()
    assert wrong == [], "\n".join(wrong)


def test_the_check_finds_a_moved_module_and_a_missing_file():
    assert module_resolves("analysis.pipeline.results.AnalysisSummary")
    assert module_resolves("webapp.api.result_schema")
    assert not module_resolves("analysis.pipeline.no_such_module")
    assert not module_resolves("webapp.api.no_such_module.thing")
    assert not file_exists("CONTRACTS.md", all_file_paths())
    assert file_exists("docs/ARCHITECTURE.md", all_file_paths())
    assert not file_exists("docs/NO_SUCH.md", all_file_paths())
    lines = prose('"""See `a.b`."""\nx = "not prose"  # a comment\n')
    assert [text for _, text in lines] == ['"""See `a.b`."""', "# a comment"]
