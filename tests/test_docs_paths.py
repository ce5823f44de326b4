"""Every module path and dotted module name that README.md and docs/ cite exists (issue 22).

A path (``analysis/kinematics/retarget.py``, ``tests/e2e/``, ``data/ui-prmd/README.md``) must be a
file or folder of the repository; a dotted name (``analysis.kinematics.map_onto``,
``workers.tasks.resume_interrupted_local_runs``, ``bench.eval_live``) must name a module, or a name
that module defines or imports (and, for a class, one of its members), read from the source
without importing it.
"""

import ast
import re
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = ("analysis", "capture", "webapp", "workers", "tests", "bench", "templates", "deploy")
PATH = re.compile(
    rf"(?<![\w./-])((?:{'|'.join((*FOLDERS, 'data', 'docs'))})/[\w./-]*[\w/])(?![\w*…{{])"
)
DOTTED = re.compile(rf"(?<![\w./-])((?:{'|'.join(FOLDERS)})(?:\.\w+)+)")


def cited_documents() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def module_file(name: str) -> Path | None:
    base = ROOT.joinpath(*name.split("."))
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


@cache
def bound_names(path: Path) -> dict[str, ast.AST | str | None]:
    """Names a module binds at its top level: definitions, assignments and imports (a name
    imported from a module: that module's dotted name for it, followed when checking)."""
    names: dict[str, ast.AST | str | None] = {}
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names[node.name] = node
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names.update({t.id: None for t in targets if isinstance(t, ast.Name)})
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.update({a.asname or a.name: f"{node.module}.{a.name}" for a in node.names})
        elif isinstance(node, ast.Import | ast.ImportFrom):
            names.update({(a.asname or a.name).split(".")[0]: None for a in node.names})
    return names


def class_members(node: ast.ClassDef) -> set[str]:
    members = set()
    for item in node.body:
        if isinstance(item, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            members.add(item.name)
        elif isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
            members.add(item.target.id)
        elif isinstance(item, ast.Assign):
            members.update(t.id for t in item.targets if isinstance(t, ast.Name))
    return members


def dotted_exists(name: str) -> bool:
    """The longest prefix that is a module, then a name it binds (and a class's member)."""
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        path = module_file(".".join(parts[:k]))
        if path is None:
            continue
        rest = parts[k:]
        if not rest:
            return True
        node = bound_names(path).get(rest[0], False)
        if node is False:
            return False
        if isinstance(node, str) and node.split(".")[0] in FOLDERS:  # re-exported: follow it
            return dotted_exists(".".join((node, *rest[1:])))
        return not (isinstance(node, ast.ClassDef) and len(rest) > 1) or (
            rest[1] in class_members(node)
        )
    return False


def missing_citations(text: str) -> list[str]:
    missing = [p for p in PATH.findall(text) if not (ROOT / p.rstrip("/.")).exists()]
    return missing + [name for name in DOTTED.findall(text) if not dotted_exists(name)]


def test_every_cited_module_path_and_name_exists():
    missing = {
        str(doc.relative_to(ROOT)): found
        for doc in cited_documents()
        if (found := sorted(set(missing_citations(doc.read_text()))))
    }
    assert missing == {}


def test_the_docs_cite_modules_at_all():
    """The patterns find what the docs cite (a check that matches nothing proves nothing)."""
    text = "\n".join(doc.read_text() for doc in cited_documents())
    assert "analysis/pipeline/run.py" in PATH.findall(text)
    assert "analysis.kinematics.map_onto" in DOTTED.findall(text)
    assert len(PATH.findall(text)) > 100 and len(DOTTED.findall(text)) > 50


def test_a_stale_citation_is_reported():
    text = (
        "See `analysis/bvh/retarget.py`, `analysis/kinematics/retarget.py`, `analysis.bvh.read`,\n"
        "`analysis.bvh.map_onto`, `analysis.online.OpenEndAligner.push`,\n"
        "`analysis.online.OpenEndAligner.pull`, `analysis.retrieval_features.FEATURES` and\n"
        "`workers.tasks.resume_interrupted_local_runs`; `data/ui-prmd/sessions/m01_s03…` is a glob."
    )
    assert missing_citations(text) == [
        "analysis/bvh/retarget.py",
        "analysis.bvh.map_onto",
        "analysis.online.OpenEndAligner.pull",
        "analysis.retrieval_features.FEATURES",
    ]
