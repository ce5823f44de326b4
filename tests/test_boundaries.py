"""analysis/ is the numerical core: it must never import the web app, Celery or Django."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FORBIDDEN = {"django", "celery", "rest_framework", "webapp", "workers", "plotly", "redis"}


def imported_top_levels(tree: ast.AST) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module.split(".")[0])
    return names


def test_analysis_imports_no_web_or_queue_code():
    offenders = {}
    for path in sorted((ROOT / "analysis").rglob("*.py")):
        bad = imported_top_levels(ast.parse(path.read_text())) & FORBIDDEN
        if bad:
            offenders[str(path.relative_to(ROOT))] = sorted(bad)
    assert offenders == {}


def test_boundary_check_catches_a_forbidden_import():
    assert imported_top_levels(ast.parse("from django.db import models")) == {"django"}


def test_nothing_reads_the_shared_folder():
    pattern = "../" + "shared"
    hits = [
        str(p.relative_to(ROOT))
        for folder in ("analysis", "capture", "workers", "webapp", "tests", "bench", "templates")
        for p in (ROOT / folder).rglob("*")
        if p.is_file() and p.suffix in {".py", ".html", ".js", ".toml"} and pattern in p.read_text()
    ]
    assert hits == []
