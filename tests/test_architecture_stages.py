"""docs/ARCHITECTURE.md's stage diagram is the pipeline's own list of its stages, drawn by
`docs/stage_diagram.py` from `analysis.pipeline.stage_order.ORDER` (issue 22)."""

import importlib.util
import re
from pathlib import Path

import pytest

from analysis.pipeline.stage_order import ORDER, Stage

ROOT = Path(__file__).resolve().parents[1]


def load_script():
    spec = importlib.util.spec_from_file_location("stage_diagram", ROOT / "docs/stage_diagram.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


script = load_script()


def between_markers(page: str) -> str:
    found = re.search(r"<!-- stages:start -->\n(.*?)\n<!-- stages:end -->", page, re.DOTALL)
    assert found, "docs/ARCHITECTURE.md holds the stage markers"
    return found.group(1)


def test_architecture_shows_exactly_the_pipelines_stage_list():
    page = (ROOT / "docs/ARCHITECTURE.md").read_text()
    assert between_markers(page) == script.diagram(ORDER)
    assert script.refreshed(page) == page


def test_the_diagram_lists_every_stage_in_the_lists_order():
    rows = [line for line in script.diagram(ORDER).splitlines() if line[:3] in ("   ", "─► ")]
    keys = [row[3:].split()[0] for row in rows[1:]]  # after the header row
    assert keys == [stage.key for stage in ORDER]
    for row, stage in zip(rows[1:], ORDER, strict=True):
        assert stage.label in row and row.endswith(stage.done_by)
        assert ("*" in row.split(stage.label)[0]) == stage.if_unfit


def test_another_order_draws_another_diagram_and_refreshes_a_stale_page():
    swapped = (ORDER[1], ORDER[0], *ORDER[2:])
    assert script.diagram(swapped) != script.diagram(ORDER)
    stale = "intro\n<!-- stages:start -->\nold\n<!-- stages:end -->\noutro\n"
    page = script.refreshed(stale, swapped)
    assert page.startswith("intro\n") and page.endswith("\noutro\n")
    assert between_markers(page) == script.diagram(swapped)
    assert between_markers(script.refreshed(page, ORDER)) == script.diagram(ORDER)


def test_the_unfit_note_follows_the_fit_check():
    order = (Stage("match", "checking", "analysis.pipeline.match"), Stage("a", "b", "c", True))
    lines = script.diagram(order).splitlines()
    at_match = next(k for k, line in enumerate(lines) if line.startswith("   match"))
    assert "only the stages marked *" in lines[at_match + 1]
    assert lines[at_match + 2].startswith("─► a *")


def test_a_page_without_markers_is_refused():
    with pytest.raises(ValueError, match="markers"):
        script.refreshed("no markers here")


def test_the_check_option_reports_a_stale_page(tmp_path, monkeypatch, capsys):
    page = tmp_path / "ARCHITECTURE.md"
    page.write_text("<!-- stages:start -->\nold\n<!-- stages:end -->\n")
    monkeypatch.setattr(script, "ARCHITECTURE", page)
    assert script.main(["--check"]) == 1
    assert script.main([]) == 0 and script.main(["--check"]) == 0
    assert between_markers(page.read_text()) == script.diagram(ORDER)
    assert "stale" in capsys.readouterr().out
