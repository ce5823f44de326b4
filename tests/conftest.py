"""Shared by every test directory: the prepared data folders of tests/local_server.py, and the
order in which the test files are handed out to the xdist workers."""

from __future__ import annotations

import os

import pytest

from tests.local_server import LocalServer


@pytest.fixture(scope="session", autouse=True)
def _prepared_data_folders(tmp_path_factory):
    """Migrating and loading the demo clinic once per run, for every LocalServer and the
    browser tests' `demo`: a folder shared by the xdist workers (their base folders' parent)."""
    base = tmp_path_factory.getbasetemp()
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    LocalServer.prepared_root = root / "prepared"


# The test files that take longest, longest first (`pytest -n 0 --durations`, 2026-11-29; the
# files outside tests/e2e by the processor time of their tests and the processes they start, see
# docs/PERFORMANCE.md): `make test` hands them out first, so that no worker is left alone with
# one of them at the end.
SLOWEST_FIRST = (
    "tests/e2e/test_camera_page.py",
    "tests/e2e/test_capture_sources.py",
    "tests/e2e/test_upload_flow.py",
    "tests/e2e/test_page_widths.py",
    "tests/e2e/test_one_pass_count.py",
    "tests/webapp/test_permissions.py",
    "tests/analysis/test_every_pair.py",
    "tests/analysis/test_hostile_files.py",
    "tests/webapp/test_upload_fuzz.py",
    "tests/analysis/test_pipeline.py",
    "tests/webapp/test_backup.py",
    "tests/analysis/test_cli.py",
    "tests/analysis/test_bvh_fuzz.py",
    "tests/analysis/test_dtw.py",
    "tests/webapp/test_exercise_sources.py",
    "tests/analysis/test_cli_without_network.py",
    "tests/analysis/test_judgement.py",
    "tests/webapp/test_no_third_party.py",
)
# Browser tests, tests marked slow and tests that start real worker processes come next.
LONG_MARKS = ("e2e", "slow", "integration")


def file_rank(path: str, items: list[pytest.Item]) -> tuple[int, int, int]:
    """Listed files in their order, then files with a long mark, then the rest with the most
    tests first (what xdist's own order would be)."""
    listed = SLOWEST_FIRST.index(path) if path in SLOWEST_FIRST else len(SLOWEST_FIRST)
    marked = any(item.get_closest_marker(name) for item in items for name in LONG_MARKS)
    return listed, 0 if marked else 1, -len(items)


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """Under xdist (`make test`, with --dist loadfile --no-loadscope-reorder) each file goes to
    one worker, in the order the files first appear: the slowest files go first. A run in one
    process keeps pytest-django's order (database tests before transactional ones)."""
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        return
    files: dict[str, list[pytest.Item]] = {}
    for item in items:
        files.setdefault(item.nodeid.split("::")[0], []).append(item)
    ordered = sorted(files.items(), key=lambda entry: file_rank(*entry))
    items[:] = [item for _, its in ordered for item in its]
