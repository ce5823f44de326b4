"""The layout rules of docs/ARCHITECTURE.md: stage packages in one stated order, small modules, no
import cycles (counting the package ``__init__`` every import runs), no network in the core."""

import ast
import re
from collections.abc import Iterable, Mapping
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROJECT = ("analysis", "capture", "workers", "webapp")
MAX_LINES = 400

# The packages of analysis/, lowest first: each imports only packages before it in this list.
# docs/ARCHITECTURE.md states the same order (test_architecture_states_the_checked_order).
ANALYSIS_ORDER = (
    "bvh", "kinematics", "sources", "dtw", "periodic", "landmarks", "online", "assessment",
    "clinical", "feedback", "adjustment", "retrieval", "pipeline", "live",
)  # fmt: skip
# What the core may never import: the network, sockets and event loops (the capture client and
# the server hold those), and the application packages above it.
NETWORK = {
    "socket", "socketserver", "ssl", "selectors", "asyncio", "websockets", "urllib", "urllib3",
    "http", "requests", "aiohttp", "httpx", "smtplib", "ftplib", "xmlrpc", "channels", "uvicorn",
}  # fmt: skip
ABOVE_THE_CORE = {"capture", "workers", "webapp"}
# The command line (`analysis/__main__.py`, the top of the core) hands its `stream` subcommand
# over to the capture client above the core (the interface contract); nothing else in the core may.
HAND_OVER = {"analysis.__main__": {"capture"}}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def project_modules() -> dict[str, Path]:
    return {
        module_name(path): path
        for package in PROJECT
        for path in (ROOT / package).rglob("*.py")
        if "migrations" not in path.parts
    }


def imported_modules(tree: ast.AST, known: set[str]) -> set[str]:
    """Project modules a file imports anywhere (function-level imports included)."""
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            # `from package import module` depends on the module; `from module import name` on
            # the module that defines or re-exports the name.
            for alias in node.names:
                submodule = f"{node.module}.{alias.name}"
                found.add(submodule if submodule in known else node.module)
    return found & known


def ancestors(name: str) -> list[str]:
    """The packages whose ``__init__`` importing ``name`` runs first: a.b.c -> [a, a.b]."""
    parts = name.split(".")
    return [".".join(parts[:k]) for k in range(1, len(parts))]


def with_parent_inits(importer: str, targets: Iterable[str], known: set[str]) -> set[str]:
    """The targets and the package ``__init__`` modules importing them runs, except the
    importer's own packages (already being imported when it runs)."""
    own = {*ancestors(importer), importer}
    found = set(targets)
    for target in targets:
        found.update(p for p in ancestors(target) if p in known and p not in own)
    return found - {importer}


def graph_of(trees: Mapping[str, ast.AST]) -> dict[str, set[str]]:
    known = set(trees)
    return {
        name: with_parent_inits(name, imported_modules(tree, known), known)
        for name, tree in trees.items()
    }


def import_graph() -> dict[str, set[str]]:
    return graph_of({name: ast.parse(path.read_text()) for name, path in project_modules().items()})


def find_cycle(graph: dict[str, set[str]]) -> list[str]:
    """One import cycle as a list of modules, or [] when the graph has none."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str]:
        state[node] = 1
        stack.append(node)
        for target in sorted(graph.get(node, ())):
            if state.get(target) == 1:
                return [*stack[stack.index(target) :], target]
            if target not in state and (cycle := visit(target)):
                return cycle
        stack.pop()
        state[node] = 2
        return []

    for start in sorted(graph):
        if start not in state and (cycle := visit(start)):
            return cycle
    return []


def layer_violations(graph: Mapping[str, set[str]], order: tuple[str, ...]) -> list[str]:
    """Imports from an analysis package of one it may not use: one at its level or above it in
    ``order``, a package ``order`` does not place, or a package above the core."""
    rank = {package: k for k, package in enumerate(order)}
    out = []
    for importer, targets in sorted(graph.items()):
        parts = importer.split(".")
        if parts[0] != "analysis" or len(parts) < 2:
            continue
        for target in sorted(targets):
            top, *rest = target.split(".")
            if top in ABOVE_THE_CORE and top not in HAND_OVER.get(importer, ()):
                out.append(f"{importer} -> {target}")
            elif top == "analysis" and rest and rest[0] != parts[1]:
                high = len(order) if parts[1] == "__main__" else rank.get(parts[1])
                low = rank.get(rest[0])
                if low is None or high is None or low >= high:
                    out.append(f"{importer} -> {target}")
    return out


def top_level_names(node: ast.Import | ast.ImportFrom) -> set[str]:
    if isinstance(node, ast.Import):
        return {alias.name.split(".")[0] for alias in node.names}
    return {node.module.split(".")[0]} if node.module and node.level == 0 else set()


def network_imports(tree: ast.AST) -> set[str]:
    return {
        name
        for node in ast.walk(tree)
        if isinstance(node, ast.Import | ast.ImportFrom)
        for name in top_level_names(node) & NETWORK
    }


def uncommented_function_imports(source: str) -> list[int]:
    """Lines of imports of project modules inside a function with no comment saying why (on the
    import's lines or the line above)."""
    lines = source.splitlines()
    out = []
    for func in ast.walk(ast.parse(source)):
        if not isinstance(func, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        for node in ast.walk(func):
            if isinstance(node, ast.Import | ast.ImportFrom) and top_level_names(node) & {*PROJECT}:
                span = lines[max(node.lineno - 2, 0) : node.end_lineno]
                if not any("#" in line for line in span):
                    out.append(node.lineno)
    return sorted(set(out))


def analysis_sources() -> dict[str, str]:
    return {
        str(path.relative_to(ROOT)): path.read_text()
        for path in sorted((ROOT / "analysis").rglob("*.py"))
    }


def test_no_import_cycle_among_project_modules():
    assert find_cycle(import_graph()) == []


def test_cycle_finder_reports_a_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}
    assert find_cycle(graph) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) == []


def test_importing_a_module_runs_its_packages_init():
    """p.low imports q.deep: q/__init__ runs first, and it imports p.high, which imports
    p.low: a cycle only the parent-__init__ edge shows."""
    trees = {
        "p": ast.parse(""),
        "p.low": ast.parse("from q.deep import thing"),
        "p.high": ast.parse("import p.low"),
        "q": ast.parse("from p.high import x"),
        "q.deep": ast.parse(""),
    }
    graph = graph_of(trees)
    assert graph["p.low"] == {"q", "q.deep"}
    assert graph["p.high"] == {"p.low"}  # its own package's __init__ is not an edge
    assert find_cycle(graph) == ["p.high", "p.low", "q", "p.high"]


def test_analysis_packages_import_only_packages_below_them():
    assert layer_violations(import_graph(), ANALYSIS_ORDER) == []


def test_every_analysis_package_has_its_place_in_the_order():
    packages = {p.name for p in (ROOT / "analysis").iterdir() if (p / "__init__.py").exists()}
    assert sorted(packages) == sorted(ANALYSIS_ORDER)


def test_layer_check_reports_an_import_from_above():
    graph = {
        "analysis.bvh.io": {"analysis.kinematics.quaternions"},
        "analysis.kinematics.fk": {"analysis.bvh.io", "analysis.kinematics"},
        "analysis.online.x": {"capture.stream", "analysis.unplaced.y"},
        "analysis.pipeline.cli": {"capture"},
        "analysis.__main__": {"capture.stream", "analysis.pipeline.run", "analysis.bvh"},
    }
    assert layer_violations(graph, ("bvh", "kinematics", "online", "pipeline")) == [
        "analysis.bvh.io -> analysis.kinematics.quaternions",
        "analysis.online.x -> analysis.unplaced.y",
        "analysis.online.x -> capture.stream",
        "analysis.pipeline.cli -> capture",  # only the command line hands over to capture
    ]


def test_the_core_imports_no_network_module():
    found = {
        path: sorted(names)
        for path, source in analysis_sources().items()
        if (names := network_imports(ast.parse(source)))
    }
    assert found == {}
    assert network_imports(ast.parse("import urllib.request\nfrom websockets import x")) == {
        "urllib",
        "websockets",
    }


def test_no_function_level_import_of_a_project_module_without_a_reason():
    found = {
        path: lines
        for path, source in analysis_sources().items()
        if (lines := uncommented_function_imports(source))
    }
    assert found == {}


def test_function_level_import_check_reports_one_without_a_comment():
    source = (
        "import numpy\n\n"
        "def f():\n    from analysis.bvh import read\n\n"
        "def g():\n    # not a cycle: bvh never imports this module\n"
        "    from analysis.bvh import read\n"
        "\ndef h():\n    import json\n"
    )
    assert uncommented_function_imports(source) == [4]


def test_architecture_states_the_checked_order():
    text = (ROOT / "docs" / "ARCHITECTURE.md").read_text()
    stated = re.search(r"Package order, lowest first: ([^.]+)\.", " ".join(text.split()))
    assert stated, "docs/ARCHITECTURE.md states the package order"
    assert tuple(re.findall(r"`(\w+)`", stated.group(1))) == ANALYSIS_ORDER


def test_workers_never_import_web_service_modules():
    """The web app's service modules enqueue the workers' tasks; workers use models and helpers."""
    found = {
        (name, target)
        for name, targets in import_graph().items()
        if name.startswith("workers")
        for target in targets
        if target.startswith("webapp.") and target.split(".")[-1] == "services"
    }
    assert found == set()


def test_analysis_has_only_packages_at_its_top():
    loose = sorted(p.name for p in (ROOT / "analysis").glob("*.py"))
    assert loose == ["__init__.py", "__main__.py"]


def test_no_module_over_the_size_limit():
    long = {
        str(path.relative_to(ROOT)): n
        for path in project_modules().values()
        if (n := len(path.read_text().splitlines())) > MAX_LINES
    }
    assert long == {}


def test_celery_tasks_live_in_workers():
    assert sorted(str(p.relative_to(ROOT)) for p in (ROOT / "webapp").rglob("tasks.py")) == []
