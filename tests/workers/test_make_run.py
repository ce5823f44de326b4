"""`make run` protects the machine, tested on the site started as `make run` starts it (the launcher
`workers.local`: runserver and a real Celery worker on the folder broker, `tests/local_server.py`):

- it serves with DEBUG off: an unknown address gets the site's own 404 page, static files are
  served, a login works over plain HTTP, the secret key was generated once, for this data folder;
- a recording whose header says ``Frame Time: 1000`` is refused (or its run fails) with the
  reason within 10 s, and the next upload is analysed;
- each pool process of the worker carries the memory ceiling, the launcher and the server do not;
  past it an analysis fails with the plain reason, and the worker analyses the next upload;
- a run whose worker dies twice (its pool process killed, then the whole worker) fails with the
  plain reason and is not claimed a third time; one past the hard time limit fails with its own;
- SIGTERM to the launcher leaves none of its processes after 10 s, even mid-analysis;
- with ``--demo`` (what `make run` runs) the page answers before the demo's recordings are
  analysed, and the worker then analyses them all.
"""

from __future__ import annotations

import gzip
import os
import re
import signal
import sqlite3
import subprocess
import sys
import time
import uuid
from pathlib import Path

import pytest
import requests

from tests.local_server import ROOT, LocalServer
from tests.personas import FIXTURES, PASSWORD
from tests.workers.test_quiet_log import check_quiet_log
from workers.limits import MEMORY_MESSAGE, died_too_often_message, time_limit_message

pytestmark = pytest.mark.slow
SQUAT = "sessions/m01_s02_correct.bvh.gz"
SETUP = """
from tests.personas import make_exercise, make_user
from webapp.accounts.models import Clinic, Role
from webapp.patients.models import Patient
clinic = Clinic.objects.create(name="Limits clinic")
therapist = make_user("limits", clinic, Role.THERAPIST)
for name in ("Ann Example", "Bo Example", "Cy Example", "Di Example"):
    patient = Patient.objects.create(clinic=clinic, display_name=name)
    patient.therapists.add(therapist)
make_exercise(clinic, source="reps/m01_s01_e01.bvh.gz")
"""
DONE = {"succeeded", "failed"}


def recording(frames: int | None = None, frame_time: str = "0.033333") -> bytes:
    """A UI-PRMD deep squat session, its header's frame time replaced; with ``frames``, its
    frames repeated up to that many (a long take)."""
    text = gzip.decompress((FIXTURES / SQUAT).read_bytes()).decode()
    head, motion = text.split("MOTION", 1)
    rows = motion.strip().splitlines()[2:]
    count = frames or len(rows)
    body = "\n".join(rows[i % len(rows)] for i in range(count))
    return gzip.compress(
        f"{head}MOTION\nFrames: {count}\nFrame Time: {frame_time}\n{body}\n".encode(), 1
    )


class Api:
    """The REST API as a practice-management system uses it, with a therapist's token."""

    def __init__(self, site: LocalServer) -> None:
        self.url = f"{site.url}/api/v1"
        answer = requests.post(
            f"{self.url}/auth/token/", json={"username": "limits", "password": PASSWORD}
        )
        answer.raise_for_status()
        self.headers = {"Authorization": f"Token {answer.json()['token']}"}
        self.patients = [p["id"] for p in self.get("/patients/")["results"]]
        self.exercise = self.get("/exercises/")["results"][0]["id"]

    def get(self, path: str) -> dict:
        answer = requests.get(f"{self.url}{path}", headers=self.headers, timeout=30)
        answer.raise_for_status()
        return answer.json()

    def upload(self, content: bytes, patient: int = 0) -> requests.Response:
        data = {"patient": self.patients[patient], "exercise": self.exercise}
        files = {"file": (f"{uuid.uuid4().hex}.bvh.gz", content)}
        return requests.post(
            f"{self.url}/recordings/", data=data, files=files, headers=self.headers, timeout=60
        )

    def wait(self, recording_id: str, seconds: float, until=lambda body: body["status"] in DONE):
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            body = self.get(f"/recordings/{recording_id}/")
            if until(body):
                return body
            time.sleep(0.2)
        raise AssertionError(f"still {body['status']} after {seconds:.0f} s: {body}")


def run_row(site: LocalServer, recording_id: str) -> dict:
    """The run's row, read from the site's SQLite file."""
    with sqlite3.connect(site.data_dir / "db.sqlite3") as db:
        db.row_factory = sqlite3.Row
        rows = db.execute(
            "SELECT * FROM recordings_analysisrun WHERE recording_id = ?",
            (uuid.UUID(recording_id).hex,),
        ).fetchall()
    assert len(rows) == 1, "one run per recording"
    return dict(rows[0])


def processes() -> dict[int, tuple[int, int, str]]:
    """Every live process: pid → (parent, process group, state)."""
    found = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        found[int(stat.parent.name)] = (int(fields[1]), int(fields[2]), fields[0])
    return found


def family(root: int) -> tuple[set[int], set[int]]:
    """The processes descending from ``root`` (itself included) and their process groups."""
    table = processes()
    members, grew = {root}, True
    while grew:
        more = {pid for pid, (parent, _, _) in table.items() if parent in members}
        grew = not more <= members
        members |= more
    return members, {table[pid][1] for pid in members if pid in table}


def survivors(members: set[int], groups: set[int]) -> list[int]:
    return sorted(
        pid
        for pid, (_, group, state) in processes().items()
        if (pid in members or group in groups) and state != "Z"
    )


def data_ceiling(pid: int) -> str:
    text = Path(f"/proc/{pid}/limits").read_text()
    return re.search(r"Max data size\s+(\S+)", text).group(1)


def pool_processes(site: LocalServer) -> list[int]:
    worker = site.worker_pid()
    return [pid for pid, (parent, _, _) in processes().items() if parent == worker]


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """`make run`, with slow analysis stages (to kill or stop the worker mid-analysis), a 1 GB
    ceiling, and the recording limits raised so that only the ceiling stops a long take (the
    frame time's own limits stay)."""
    server = LocalServer(tmp_path_factory.mktemp("make-run-slow"), demo=False, setup=SETUP)
    server.extra_env = {
        "ANALYSIS_STAGE_DELAY_SECONDS": "1.0",
        "ANALYSIS_MEMORY_LIMIT_MB": "1024",
        "RECORDING_MAX_SECONDS": "1e9",
        "RECORDING_MAX_FRAMES": "100000000",
        "RECORDING_MAX_ANALYSIS_BYTES": str(1 << 45),
    }
    with server:
        yield server


def test_debug_is_off_and_an_unknown_address_gets_the_friendly_404_page(site):
    session = requests.Session()
    login = session.get(f"{site.url}/accounts/login/")
    token = session.cookies["csrftoken"]
    answer = session.post(
        login.url,
        data={"username": "limits", "password": PASSWORD, "csrfmiddlewaretoken": token},
        headers={"Referer": login.url},
    )
    assert answer.ok and "/accounts/login" not in answer.url, "a login works over plain HTTP"
    for address in (f"/recordings/{uuid.uuid4()}/", "/no-such-page/"):
        page = session.get(site.url + address)
        assert page.status_code == 404
        assert "We could not find this page" in page.text
        assert "URLconf" not in page.text and "DEBUG = True" not in page.text
    assert session.get(f"{site.url}/static/css/app.css").status_code == 200
    key = site.data_dir / "secret_key"
    assert key.stat().st_mode & 0o777 == 0o600 and len(key.read_text().strip()) >= 50


def test_frame_time_1000_is_refused_within_10_s_and_the_next_upload_is_analysed(site):
    api = Api(site)
    started = time.monotonic()
    answer = api.upload(recording(frame_time="1000"))
    if answer.status_code == 201:  # accepted: then its run fails with the reason
        body = api.wait(answer.json()["id"], 10)
        assert body["status"] == "failed"
        reason = body["run"]["user_error"]
    else:
        assert answer.status_code == 400, answer.text
        reason = answer.text
    assert time.monotonic() - started < 10
    assert "frame" in reason.lower() and "unexpectedly" not in reason, reason
    assert "Traceback" not in reason

    created = api.upload(recording(), patient=1)
    assert created.status_code == 201, created.text
    body = api.wait(created.json()["id"], 180)
    assert body["status"] == "succeeded", site.log_tail()


def test_each_pool_process_has_the_memory_ceiling_and_nothing_else_has(site):
    pool = pool_processes(site)
    assert len(pool) >= 2, "two analyses at a time, and beat"
    ceilings = {pid: data_ceiling(pid) for pid in pool}
    assert list(ceilings.values()).count(str(1024 * 1024 * 1024)) >= 2, ceilings
    assert data_ceiling(site.process.pid) == "unlimited"  # the launcher
    assert data_ceiling(site.worker_pid()) == "unlimited"  # the worker's main process


def test_an_analysis_past_the_memory_ceiling_fails_with_the_plain_reason(site):
    """60,000 frames at 10 frames per second, resampled to 30: past a 1 GB ceiling."""
    api = Api(site)
    answer = api.upload(recording(frames=60_000, frame_time="0.1"))
    assert answer.status_code == 201, answer.text
    body = api.wait(answer.json()["id"], 120)
    assert body["status"] == "failed", site.log_tail()
    assert body["run"]["user_error"] == MEMORY_MESSAGE
    assert run_row(site, answer.json()["id"])["attempts"] == 1
    assert site.running()


def running_in(api: Api, site: LocalServer, recording_id: str, attempts: int) -> dict:
    """Wait until the run is under way (past its first stage) in its ``attempts``th claim."""

    def under_way(body: dict) -> bool:
        assert body["status"] != "failed", body
        return body["status"] == "running" and body["progress"] > 5

    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        api.wait(recording_id, 120, until=under_way)
        row = run_row(site, recording_id)
        if row["attempts"] == attempts:
            return row
        time.sleep(0.2)
    raise AssertionError(f"attempt {row['attempts']}, not {attempts}:\n" + site.log_tail())


def test_a_run_whose_worker_dies_twice_fails_with_the_reason_and_no_third_attempt(site):
    api = Api(site)
    created = api.upload(recording(), patient=2)
    assert created.status_code == 201, created.text
    recording_id = created.json()["id"]

    first = running_in(api, site, recording_id, attempts=1)
    pool_pid = int(first["worker"].rsplit(" pid ", 1)[1])
    assert pool_pid in pool_processes(site)
    os.kill(pool_pid, signal.SIGKILL)  # its pool process, as the out-of-memory killer would

    running_in(api, site, recording_id, attempts=2)  # released and claimed again at once
    worker = site.worker_pid()
    os.killpg(worker, signal.SIGKILL)  # then the whole worker

    body = api.wait(recording_id, 60)
    assert body["status"] == "failed"
    assert body["run"]["user_error"] == died_too_often_message(2)
    time.sleep(3)  # a third claim, if any, would happen now
    row = run_row(site, recording_id)
    assert (row["status"], row["attempts"]) == ("failed", 2)
    log = site.log_tail(600)
    assert "interrupted analyses: 0 queued again, 1 failed" in log
    assert site.worker_pid() != worker, "the launcher started a new worker"


def test_an_analysis_past_the_hard_time_limit_fails_with_the_plain_reason(site, tmp_path):
    """A 4 s hard limit (no soft limit before it) and slow stages: Celery kills the pool process
    and the worker's main process fails the run with the time limit's reason; the worker lives.
    A second launcher of its own, on a copy of the first one's database and its files."""
    server = LocalServer(tmp_path / "make-run-hard", demo=False)
    server.data_dir.mkdir()
    with (
        sqlite3.connect(site.data_dir / "db.sqlite3") as source,
        sqlite3.connect(server.data_dir / "db.sqlite3") as copy,
    ):
        source.backup(copy)
    server.extra_env = {
        "MEDIA_ROOT": str(site.data_dir / "media"),
        "ANALYSIS_STAGE_DELAY_SECONDS": "1.0",
        "ANALYSIS_SOFT_TIME_LIMIT": "0",  # none
        "ANALYSIS_TIME_LIMIT": "4",
    }
    server.start()
    try:
        api = Api(server)
        created = api.upload(recording(), patient=3)
        assert created.status_code == 201, created.text
        body = api.wait(created.json()["id"], 60)
        assert body["status"] == "failed", server.log_tail()
        assert body["run"]["user_error"] == time_limit_message(4)
        assert "Hard time limit (4" in server.log_tail(400) and server.running()
    finally:
        server.stop()


def test_a_refusal_is_one_line_and_a_successful_poll_none(site):
    check_quiet_log(site, "limits", Api(site).exercise)  # tests/workers/test_quiet_log.py


def test_sigterm_to_the_launcher_leaves_none_of_its_processes_after_10_s(site):
    api = Api(site)
    created = api.upload(recording(), patient=3)
    assert created.status_code == 201, created.text
    running_in(api, site, created.json()["id"], attempts=1)  # mid-analysis
    launcher = site.process
    members, groups = family(launcher.pid)
    assert len(members) >= 5, "launcher, server, worker, its pool and beat"

    launcher.send_signal(signal.SIGTERM)
    started = time.monotonic()
    while survivors(members, groups) and time.monotonic() - started < 10:
        time.sleep(0.1)
    left = survivors(members, groups)
    assert not left, f"still running after 10 s: {left}\n" + site.log_tail()
    assert launcher.wait(timeout=1) == 0
    assert "stopping (SIGTERM)" in site.log_tail()


def demo_runs(site: LocalServer) -> list[str]:
    """The status of each analysis run in the site's database."""
    with sqlite3.connect(site.data_dir / "db.sqlite3") as db:
        return [row[0] for row in db.execute("SELECT status FROM recordings_analysisrun")]


def test_make_run_serves_the_page_first_and_the_worker_analyses_the_demo(tmp_path):
    """`make run` (`workers.local --demo`): the page answers while the demo's recordings are
    still queued or being analysed, as the therapist's recordings list says; the worker then
    analyses every one and builds each exercise's first model."""
    site = LocalServer(tmp_path / "make-run-demo", demo=False)
    site.prepare()  # migrated, nothing loaded: the launcher loads the demo itself
    with site.log_path.open("ab") as log:
        site.process = subprocess.Popen(
            [sys.executable, "-m", "workers.local", "--demo", f"127.0.0.1:{site.port}"],
            cwd=ROOT, env=site.env(), stdout=log, stderr=subprocess.STDOUT,
            start_new_session=True,
        )  # fmt: skip
    try:
        deadline = time.monotonic() + 120
        while not site.answers():
            assert site.running() and time.monotonic() < deadline, site.log_tail()
            time.sleep(0.2)
        statuses = demo_runs(site)
        assert len(statuses) == 6 and not set(statuses) <= DONE, statuses
        token = requests.post(
            f"{site.url}/api/v1/auth/token/",
            json={"username": "demo-therapist", "password": "demo-therapist-pw"},
        ).json()["token"]
        headers = {"Authorization": f"Token {token}"}
        with sqlite3.connect(site.data_dir / "db.sqlite3") as db:
            ids = [uuid.UUID(row[0]) for row in db.execute("SELECT id FROM recordings_recording")]
        pages = [f"{site.url}/api/v1/recordings/{pk}/" for pk in ids]
        shown = {requests.get(page, headers=headers, timeout=30).json()["status"] for page in pages}
        assert shown & {"queued", "running"}, shown
        while set(demo_runs(site)) != {"succeeded"}:
            assert site.running() and time.monotonic() < deadline + 300, site.log_tail()
            time.sleep(1)
        with sqlite3.connect(site.data_dir / "db.sqlite3") as db:
            versions = db.execute(
                "SELECT m.version FROM exercises_exercise e "
                "JOIN exercises_exercisemodel m ON m.id = e.active_model_id"
            ).fetchall()
        assert sorted(versions) == [(1,), (1,), (1,)], "one model built per exercise"
    finally:
        site.stop()
