"""A real Celery worker process on the real broker, sharing the test database and media folder.

These fixtures need PostgreSQL (``DATABASE_URL``) and Redis (``REDIS_URL``), which CI provides.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
from django.db import connection

ROOT = Path(__file__).resolve().parents[2]


def services_available() -> bool:
    return os.environ.get("DATABASE_URL", "").startswith("postgres") and bool(
        os.environ.get("REDIS_URL")
    )


needs_services = pytest.mark.skipif(
    not services_available(), reason="needs DATABASE_URL (PostgreSQL) and REDIS_URL (CI sets both)"
)


def test_database_url() -> str:
    """The URL of the database pytest-django created, for the worker process."""
    params = connection.settings_dict
    user = params.get("USER") or "postgres"
    host = params.get("HOST") or "127.0.0.1"
    port = params.get("PORT") or 5432
    return f"postgres://{user}@{host}:{port}/{params['NAME']}"


class Worker:
    def __init__(
        self, queue: str, media_root: Path, log_path: Path, extra_env: dict[str, str] | None = None
    ) -> None:
        self.queue = queue
        self.media_root = media_root
        self.log_path = log_path
        self.extra_env = extra_env or {}
        self.process: subprocess.Popen[bytes] | None = None

    def env(self) -> dict[str, str]:
        return {
            **os.environ,
            "DATABASE_URL": test_database_url(),
            "MEDIA_ROOT": str(self.media_root),
            "CELERY_QUEUE": self.queue,
            **self.extra_env,
        }

    def start(self) -> None:
        command = [
            sys.executable,
            "-m",
            "celery",
            "-A",
            "workers",
            "worker",
            "--pool=solo",
            "--loglevel=INFO",
            "--without-gossip",
            "--without-mingle",
            "-Q",
            self.queue,
            "-n",
            f"{self.queue}@%h",
        ]
        log = self.log_path.open("ab")
        self.process = subprocess.Popen(command, cwd=ROOT, env=self.env(), stdout=log, stderr=log)
        self.wait_until_ready()

    def wait_until_ready(self, timeout: float = 60.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if "ready." in self.log_path.read_text(errors="replace"):
                return
            assert self.process is not None and self.process.poll() is None, self.log()
            time.sleep(0.2)
        raise AssertionError("worker did not start:\n" + self.log())

    def kill(self, sig: int) -> None:
        assert self.process is not None
        self.process.send_signal(sig)
        self.process.wait(timeout=30)

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.process.kill()

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")


@pytest.fixture
def celery_queue(settings, tmp_path) -> Iterator[str]:
    """Route this test's tasks to a queue of its own on the real broker."""
    from workers import app

    queue = f"test-{uuid.uuid4().hex[:10]}"
    settings.MEDIA_ROOT = tmp_path / "media"
    saved = (app.conf.task_always_eager, app.conf.task_default_queue)
    app.conf.task_always_eager = False
    app.conf.task_default_queue = queue
    yield queue
    app.conf.task_always_eager, app.conf.task_default_queue = saved


@pytest.fixture
def worker(celery_queue, settings, tmp_path) -> Iterator[Worker]:
    running = Worker(celery_queue, Path(settings.MEDIA_ROOT), tmp_path / "worker.log")
    running.start()
    yield running
    running.stop()


@pytest.fixture(autouse=True)
def _fast_password_hashing(settings):
    """Tests create many users: a cheap hasher keeps them fast (production uses the default)."""
    settings.PASSWORD_HASHERS = ["django.contrib.auth.hashers.MD5PasswordHasher"]
