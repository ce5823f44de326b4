"""Start the site the way `make run` does, on a free port with a fresh data folder.

`make run` runs ``python -m workers.local --demo`` (the server migrates and loads the demo clinic,
then serves; a real Celery worker on the filesystem broker beside it). `LocalServer` does the same
in a folder of its own, so browser tests and `bench/bench_upload.py` exercise the real background
worker, never eager tasks; only its demo is analysed before the server starts (`load_demo --wait`),
so tests find it analysed. Only tests and benchmarks use it.

Under pytest, `LocalServer.prepared_root` (set by tests/conftest.py) makes migrating and loading
the demo a once-per-run cost: the first server of each kind prepares a folder under a lock shared
by the xdist workers, and every server after it starts from a copy of that folder.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Callable
from pathlib import Path
from typing import ClassVar

ROOT = Path(__file__).resolve().parents[1]
DATA_FILES = ("db.sqlite3", "db.sqlite3-wal", "db.sqlite3-shm", "media")


def made_once(target: Path, make: Callable[[Path], None]) -> Path:
    """``make(target)`` the first time any process of this run asks, under a file lock; the
    others wait for it and then read what it made."""
    target.parent.mkdir(parents=True, exist_ok=True)
    done = target.parent / f"{target.name}.done"
    with (target.parent / f"{target.name}.lock").open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not done.exists():
            make(target)
            done.touch()
    return target


def prepared_folder(root: Path, *, demo: bool) -> Path:
    """A data folder migrated (and with the demo clinic loaded): made once per run."""
    return made_once(
        root / ("demo" if demo else "migrated"),
        lambda folder: LocalServer(folder, demo=demo).migrate_and_load(),
    )


def copy_data(source: Path, target: Path) -> None:
    """The database and stored files of a prepared folder into ``target`` (not its log)."""
    target.mkdir(parents=True, exist_ok=True)
    for name in DATA_FILES:
        if (source / name).is_dir():
            shutil.copytree(source / name, target / name, dirs_exist_ok=True)
        elif (source / name).exists():
            shutil.copy2(source / name, target / name)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


class LocalServer:
    """``with LocalServer(data_dir) as server: server.url`` (set-up commands run first)."""

    # Where this test run keeps its prepared folders (None: each server migrates on its own).
    prepared_root: ClassVar[Path | None] = None

    def __init__(self, data_dir: Path, *, demo: bool = True, setup: str = "") -> None:
        self.data_dir = Path(data_dir)
        self.demo = demo
        self.setup = setup  # Python run with `manage.py shell -c` after migrating
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.log_path = self.data_dir / "server.log"
        self.process: subprocess.Popen[bytes] | None = None
        self.extra_env: dict[str, str] = {}  # e.g. a stage delay, so progress can be watched

    def env(self) -> dict[str, str]:
        env = {k: v for k, v in os.environ.items() if k not in ("REDIS_URL", "DATABASE_URL")}
        env.update(DATA_DIR=str(self.data_dir), DJANGO_SETTINGS_MODULE="webapp.settings")
        env.update(DEMO_ALLOWED="1")
        env.pop("LOCAL_BROKER_DIR", None)
        env.update(self.extra_env)
        return env

    def manage(self, *args: str) -> None:
        with self.log_path.open("ab") as log:
            subprocess.run(
                [sys.executable, "manage.py", *args], cwd=ROOT, env=self.env(), check=True,
                stdout=log, stderr=subprocess.STDOUT,
            )  # fmt: skip

    def prepare(self) -> None:
        """What `make run`'s prerequisites do: migrate, then the demo clinic (or `setup`)."""
        self.data_dir.mkdir(parents=True, exist_ok=True)
        if self.prepared_root is None:
            self.migrate_and_load()
        else:  # the same database and files, made by the first server of this run
            copy_data(prepared_folder(self.prepared_root, demo=self.demo), self.data_dir)
        if self.setup:
            self.manage("shell", "-c", self.setup)

    def migrate_and_load(self) -> None:
        self.data_dir.mkdir(parents=True, exist_ok=True)
        self.manage("migrate", "--noinput", "-v0")
        if self.demo:
            self.manage("load_demo", "--wait")  # analysed before the server starts, as `make demo`

    def start(self, timeout: float = 120.0) -> None:
        log = self.log_path.open("ab")
        self.process = subprocess.Popen(
            [sys.executable, "-m", "workers.local", f"127.0.0.1:{self.port}"],
            cwd=ROOT, env=self.env(), stdout=log, stderr=subprocess.STDOUT,
            start_new_session=True,
        )  # fmt: skip
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"the server ended; see {self.log_path}")
            if self.answers() and self.worker_ready():
                return
            time.sleep(0.5)
        raise TimeoutError(f"the server did not answer in {timeout:.0f} s; see {self.log_path}")

    def answers(self) -> bool:
        try:
            with urllib.request.urlopen(f"{self.url}/accounts/login/", timeout=2) as answer:
                return answer.status == 200
        except OSError:
            return False

    def worker_ready(self) -> bool:
        return b"ready." in self.log_path.read_bytes()

    def worker_pid(self) -> int:
        """The Celery worker the launcher started (in a process group of its own)."""
        assert self.process is not None
        for stat in Path("/proc").glob("[0-9]*/stat"):
            try:
                parent = int(stat.read_text().rsplit(")", 1)[1].split()[1])
                command = (stat.parent / "cmdline").read_bytes()
            except OSError:
                continue
            if parent == self.process.pid and b"celery" in command:
                return int(stat.parent.name)
        raise AssertionError("no worker under the launcher:\n" + self.log_tail())

    def running(self) -> bool:
        return self.process is not None and self.process.poll() is None

    def log_tail(self, lines: int = 80) -> str:
        """The end of the server's and worker's log, for a failing test's message."""
        text = self.log_path.read_text(errors="replace").splitlines()
        return "\n".join(text[-lines:])

    def stop(self) -> None:
        """SIGTERM to the launcher (it stops its worker and server), then to its whole group."""
        if self.process is None:
            return
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait()
        self.process = None

    def __enter__(self) -> LocalServer:
        self.prepare()
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
