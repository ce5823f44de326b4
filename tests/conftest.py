"""The suite's order: the longest test files first.

`make test` hands whole files to its processes (`--dist loadfile`) in collection order, so a long
file collected last runs alone while the other processes have finished: the suite lasts as long
as its last file. Starting with the longest files (measured with `--durations`) and ending with
the many short ones keeps every process busy to the end.
"""

from __future__ import annotations

import pytest

# Longest first (seconds on the 2-core CI machine, 2026-11-27, including module set-up).
LONGEST_FILES = (
    "tests/e2e/test_upload_flow.py",  # ~115
    "tests/workers/test_make_run.py",  # ~100
    "tests/analysis/test_hostile_files.py",  # ~100
    "tests/e2e/test_capture_sources.py",  # ~90
    "tests/analysis/test_sources_roundtrip.py",  # ~85
    "tests/webapp/test_upload_fuzz.py",  # ~65
    "tests/e2e/test_live_dashboard.py",  # ~60
    "tests/e2e/test_proxy_routing.py",  # ~60
    "tests/analysis/test_every_pair.py",  # ~60
    "tests/workers/test_faults.py",  # ~60
    "tests/e2e/test_live_page.py",  # ~45
    "tests/e2e/test_upload_recognition.py",  # ~45
    "tests/analysis/test_pipeline.py",  # ~40
    "tests/workers/test_worker_crash.py",  # ~36
    "tests/webapp/test_schemathesis.py",  # ~35
    "tests/analysis/test_sources_video.py",  # ~30
)


def file_rank(path: str) -> tuple[int, int]:
    if path in LONGEST_FILES:
        return (0, LONGEST_FILES.index(path))
    # browser and worker tests start servers and browsers: longer than the rest, on the whole
    return (1 if path.startswith(("tests/e2e/", "tests/workers/", "tests/live/")) else 2, 0)


@pytest.hookimpl(trylast=True)  # after pytest-django, which also sorts
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    # a stable sort by file: each file's tests stay together and in their own order
    items.sort(key=lambda item: file_rank(item.nodeid.split("::")[0]))
