"""How fast the upload page answers under `make run`, and that the analysis then reaches done.

Starts the site the way `make run` does (`tests/local_server.py`: migrate, demo clinic, then
``python -m workers.local``: the server and a real Celery worker on the filesystem broker) on a
free port with a fresh data folder, logs in as the demo therapist, uploads five UI-PRMD deep-squat
sessions (the copies under data/ui-prmd) through the upload page, each sent ``--think`` seconds
(2) after the page is shown, as a person choosing the file, and prints the median time from
sending the form to the answer (target: under 1 s) and the first upload's time on its own.
Each recording page must then show its analysis going from queued or running to done.

    .venv/bin/python -m bench.bench_upload [--runs 5] [--think 2] [--keep DIR]
"""

from __future__ import annotations

import argparse
import re
import statistics
import sys
import tempfile
import time
from pathlib import Path

import requests
from requests.adapters import HTTPAdapter
from urllib3.util.retry import Retry

from tests.local_server import LocalServer

ROOT = Path(__file__).resolve().parents[1]
SESSIONS = [ROOT / f"data/ui-prmd/sessions/m01_s{s:02d}_correct.bvh.gz" for s in (3, 4, 5, 6, 7)]
TARGET_S = 1.0
DONE_TIMEOUT_S = 900.0


def csrf_of(html: str) -> str:
    return re.search(r'name="csrfmiddlewaretoken" value="([^"]+)"', html).group(1)


def option_value(html: str, select_id: str, label: str) -> str:
    select = re.search(rf'<select[^>]*id="{select_id}".*?</select>', html, re.S).group(0)
    return re.search(rf'<option value="([^"]+)"[^>]*>\s*{re.escape(label)}', select).group(1)


def log_in(session: requests.Session, url: str) -> None:
    page = session.get(f"{url}/accounts/login/")
    answer = session.post(
        f"{url}/accounts/login/",
        data={
            "username": "demo-therapist",
            "password": "demo-therapist-pw",
            "csrfmiddlewaretoken": csrf_of(page.text),
        },
        headers={"Referer": f"{url}/accounts/login/"},
    )
    if "/accounts/login" in answer.url:
        raise SystemExit("could not log in as the demo therapist")


def upload(session: requests.Session, url: str, path: Path, think: float) -> tuple[float, str, str]:
    """(seconds to the answer, recording page URL, run state right after) for one upload; the
    form is sent ``think`` seconds after the page is shown (a person choosing the file)."""
    form = session.get(f"{url}/recordings/upload/").text
    time.sleep(think)
    data = {
        "csrfmiddlewaretoken": csrf_of(form),
        "patient": option_value(form, "id_patient", "Pat Patient"),
        "exercise": option_value(form, "id_exercise", "Deep squat"),
        "pain_score": "2",
        "note": "",
    }
    with path.open("rb") as handle:
        files = {"file": (path.name, handle.read(), "application/gzip")}
    start = time.perf_counter()
    answer = session.post(
        f"{url}/recordings/upload/",
        data=data,
        files=files,
        allow_redirects=False,
        headers={"Referer": f"{url}/recordings/upload/"},
    )
    elapsed = time.perf_counter() - start
    if answer.status_code != 302:
        raise SystemExit(f"upload of {path.name} answered {answer.status_code}")
    page = url + answer.headers["Location"]
    state = session.get(page.rstrip("/") + "/status/").json()["status"]
    return elapsed, page, state


def wait_done(session: requests.Session, page: str) -> list[tuple[str, int]]:
    """The (state, progress) seen on the recording's status until it ends; raises if it fails."""
    seen: list[tuple[str, int]] = []
    deadline = time.monotonic() + DONE_TIMEOUT_S
    while time.monotonic() < deadline:
        run = session.get(page.rstrip("/") + "/status/").json()
        if not seen or seen[-1] != (run["status"], run["progress"]):
            seen.append((run["status"], run["progress"]))
        if run["status"] == "succeeded":
            html = session.get(page).text
            if 'data-status="succeeded"' not in html:
                raise SystemExit(f"{page} does not show the finished analysis")
            return seen
        if run["status"] == "failed":
            raise SystemExit(f"the analysis of {page} failed: {run['error']}")
        time.sleep(0.5)
    raise SystemExit(f"the analysis of {page} did not finish in {DONE_TIMEOUT_S:.0f} s")


def polling_session() -> requests.Session:
    """A browser-like session: a GET that meets runserver reloading (another edit in the
    checkout) is tried again, as the recording page's poller does."""
    session = requests.Session()
    retry = Retry(total=20, connect=20, read=20, backoff_factor=0.5, allowed_methods=["GET"])
    session.mount("http://", HTTPAdapter(max_retries=retry))
    return session


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument(
        "--think", type=float, default=2.0, help="seconds between showing the form and sending it"
    )
    parser.add_argument("--keep", type=Path, help="data folder to use and keep (default: temp)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bench-upload-") as tmp:
        folder = args.keep or Path(tmp)
        started = time.perf_counter()
        with LocalServer(folder) as server:
            ready = time.perf_counter() - started
            print(f"server and worker ready in {ready:.0f} s ({server.url})")
            session = polling_session()
            log_in(session, server.url)
            chosen = SESSIONS[: args.runs]
            results = [upload(session, server.url, path, args.think) for path in chosen]
            for (seconds, _, state), path in zip(results, SESSIONS, strict=False):
                print(f"{path.name}: answered in {seconds:.3f} s, analysis {state}")
            for _, page, _ in results:
                seen = wait_done(session, page)
                print(f"{page}: " + " -> ".join(f"{s} {p}%" for s, p in seen))
    median = statistics.median(seconds for seconds, _, _ in results)
    immediate = sum(state in ("queued", "running") for _, _, state in results)
    print(
        f"median upload answer: {median:.3f} s over {len(results)} uploads (target < {TARGET_S} s)"
    )
    print(f"first upload after the server started: {results[0][0]:.3f} s")
    print(f"answered before the analysis ended: {immediate}/{len(results)}; all reached done")
    return 0 if median < TARGET_S and immediate == len(results) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
