"""`make run`'s broker: the launcher's environment turns eager tasks into a real filesystem
broker in the data folder; without it (tests, manage.py) tasks stay eager; Redis wins."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

from workers.local import local_env, server_command, supervise, worker_command

ROOT = Path(__file__).resolve().parents[2]
SHOW = (
    "import json, django; django.setup(); from django.conf import settings as s; "
    "print(json.dumps([s.CELERY_BROKER_URL, s.CELERY_TASK_ALWAYS_EAGER, "
    "s.CELERY_BROKER_TRANSPORT_OPTIONS.get('data_folder_in', ''), "
    "s.DATABASES['default'].get('OPTIONS', {}).get('timeout')]))"
)


def settings_under(env: dict[str, str]) -> list:
    base = {"PATH": "/usr/bin:/bin", "DJANGO_SETTINGS_MODULE": "webapp.settings"}
    answer = subprocess.run(
        [sys.executable, "-c", SHOW],
        cwd=ROOT,
        env={**base, **env},
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(answer.stdout.strip().splitlines()[-1])


def test_launcher_environment_makes_a_real_broker_in_the_data_folder(tmp_path):
    env = local_env({"DATA_DIR": str(tmp_path)})
    assert env["LOCAL_BROKER_DIR"] == str(tmp_path / "broker")
    assert (tmp_path / "broker" / "queue").is_dir()
    broker, eager, folder, timeout = settings_under(
        {"DATA_DIR": str(tmp_path), "LOCAL_BROKER_DIR": env["LOCAL_BROKER_DIR"]}
    )
    assert broker == "filesystem://" and eager is False
    assert folder == str(tmp_path / "broker" / "queue") and timeout == 30


def test_without_the_launcher_tasks_stay_eager_and_redis_wins(tmp_path):
    broker, eager, _, _ = settings_under({"DATA_DIR": str(tmp_path)})
    assert broker == "memory://" and eager is True
    broker, eager, _, _ = settings_under(
        {
            "DATA_DIR": str(tmp_path),
            "LOCAL_BROKER_DIR": str(tmp_path / "broker"),
            "REDIS_URL": "redis://127.0.0.1:6399/0",
        }
    )
    assert broker == "redis://127.0.0.1:6399/0" and eager is False


def test_worker_consumes_every_queue_with_beat_and_the_server_is_runserver(tmp_path):
    command = worker_command({"DATA_DIR": str(tmp_path)})
    assert command[command.index("-A") + 1] == "workers" and "-B" in command
    assert "-Q" not in command, "no -Q: every queue (analyses, models, reports)"
    assert f"--schedule={tmp_path / 'celerybeat-schedule'}" in command
    assert server_command("127.0.0.1:9")[-2:] == ["runserver", "127.0.0.1:9"]


def test_a_worker_that_dies_is_started_again_and_the_server_ending_stops_all(tmp_path):
    """The launcher's supervision with two small programs in place of Celery and runserver: the
    first worker dies at once (as under the out-of-memory killer), the second keeps running; the
    server ends after a few seconds, which stops the worker and the launcher."""
    starts = tmp_path / "starts"
    worker = (
        "import pathlib, sys, time\n"
        f"p = pathlib.Path({str(starts)!r})\n"
        "n = int(p.read_text()) if p.exists() else 0\n"
        "p.write_text(str(n + 1))\n"
        "sys.exit(9) if n == 0 else time.sleep(120)\n"
    )
    server = "import time; time.sleep(4)"
    code = supervise([sys.executable, "-c", worker], [sys.executable, "-c", server], os.environ)
    assert code == 0
    assert starts.read_text() == "2", "the dead worker was started once more"


def test_a_worker_that_keeps_dying_stops_the_launcher_with_its_code(tmp_path):
    server = "import time; time.sleep(120)"
    dying = [sys.executable, "-c", "import sys; sys.exit(7)"]
    started = time.monotonic()
    code = supervise(dying, [sys.executable, "-c", server], os.environ)
    assert code == 7
    assert time.monotonic() - started < 60, "the server was stopped, not waited for"
