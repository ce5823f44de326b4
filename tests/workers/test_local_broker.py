"""`make run`'s broker: the launcher's environment turns eager tasks into a real filesystem
broker in the data folder; without it (tests, manage.py) tasks stay eager; Redis wins."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from tests.local_server import free_port
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
    # `make run` (--demo): migrations and the demo clinic in the server's own process.
    demo = server_command("127.0.0.1:9", reload=False, demo=True)
    assert demo[-3:] == ["serve_demo", "--noreload", "127.0.0.1:9"]


def test_after_a_server_that_prepares_the_database_the_worker_starts_once_it_answers(tmp_path):
    """With ``worker_after`` (`make run`: the server migrates first) the worker starts only once
    the server answers on its port; a server that ends before answering leaves no worker."""
    port = free_port()
    address = f"127.0.0.1:{port}"
    seen = tmp_path / "seen"
    worker = (
        "import pathlib, time\nfrom workers.local import answers\n"
        f"pathlib.Path({str(seen)!r}).write_text(str(answers({address!r})))\n"
        "time.sleep(120)\n"
    )
    server = (
        "import socket, time\ntime.sleep(3)\n"
        f"listening = socket.create_server(('127.0.0.1', {port}))\ntime.sleep(5)\n"
    )
    workers = [sys.executable, "-c", worker]
    code = supervise(workers, [sys.executable, "-c", server], os.environ, worker_after=address)
    assert code == 0 and seen.read_text() == "True", "the worker started after the server answered"
    seen.unlink()
    failing = [sys.executable, "-c", "import sys, time; time.sleep(1); sys.exit(3)"]
    assert supervise(workers, failing, os.environ, worker_after=address) == 3
    assert not seen.exists(), "no worker for a server that never answered"


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


STUBBORN = (
    "import os, signal, subprocess, sys, time\n"
    "signal.signal(signal.SIGTERM, signal.SIG_IGN)\n"  # ignores SIGTERM, and so does its child
    "subprocess.Popen([sys.executable, '-c', 'import signal, time; "
    "signal.signal(signal.SIGTERM, signal.SIG_IGN); time.sleep(120)'])\n"
    "time.sleep(120)\n"
)


def descendants(root: int) -> set[int]:
    table = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if fields[0] != "Z":
            table[int(stat.parent.name)] = int(fields[1])
    found, grew = {root}, True
    while grew:
        more = {pid for pid, parent in table.items() if parent in found}
        grew = not more <= found
        found |= more
    return found - {root}


def alive(pids: set[int]) -> set[int]:
    def running(pid: int) -> bool:
        try:
            return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
        except OSError:
            return False

    return {pid for pid in pids if running(pid)}


def test_sigterm_stops_what_the_launcher_started_even_what_ignores_sigterm(tmp_path):
    """A worker and a server that ignore SIGTERM, each with a child that ignores it too: SIGTERM
    to the launcher ends all four within STOP_SECONDS (then SIGKILL to their process groups)."""
    script = (
        "import sys\nfrom workers.local import supervise\n"
        f"program = [sys.executable, '-c', {STUBBORN!r}]\n"
        "sys.exit(supervise(program, program, {'PATH': '/usr/bin:/bin'}))\n"
    )
    launcher = subprocess.Popen([sys.executable, "-c", script], cwd=ROOT)
    deadline = time.monotonic() + 30
    while len(descendants(launcher.pid)) < 4 and time.monotonic() < deadline:
        time.sleep(0.1)
    started = descendants(launcher.pid)
    assert len(started) == 4, started
    launcher.send_signal(signal.SIGTERM)
    stopped = time.monotonic()
    assert launcher.wait(timeout=15) == 0
    while alive(started) and time.monotonic() - stopped < 10:
        time.sleep(0.1)
    assert not alive(started), "nothing the launcher started outlives it"
    assert time.monotonic() - stopped < 10


def test_what_the_launcher_started_dies_with_it_when_it_is_killed(tmp_path):
    """SIGKILL to the launcher (no chance to clean up): its children die with it (the kernel's
    parent-death signal)."""
    script = (
        "import sys\nfrom workers.local import supervise\n"
        "program = [sys.executable, '-c', 'import time; time.sleep(120)']\n"
        "supervise(program, program, {'PATH': '/usr/bin:/bin'})\n"
    )
    launcher = subprocess.Popen([sys.executable, "-c", script], cwd=ROOT)
    deadline = time.monotonic() + 30
    while len(descendants(launcher.pid)) < 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    children = descendants(launcher.pid)
    assert len(children) == 2
    launcher.kill()
    launcher.wait()
    deadline = time.monotonic() + 5
    while alive(children) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not alive(children)


def test_the_launcher_serves_with_debug_off_and_a_secret_key_of_its_own(tmp_path):
    env = local_env({"DATA_DIR": str(tmp_path)})
    assert env["DEBUG"] == "0" and env["SECURE_SSL_REDIRECT"] == "0"
    assert env["WHITENOISE_USE_FINDERS"] == "1"
    key = env["SECRET_KEY"]
    assert len(key) >= 50 and (tmp_path / "secret_key").stat().st_mode & 0o777 == 0o600
    assert local_env({"DATA_DIR": str(tmp_path)})["SECRET_KEY"] == key, "generated once"
    assert local_env({"DATA_DIR": str(tmp_path / "other")})["SECRET_KEY"] != key
    mine = local_env({"DATA_DIR": str(tmp_path), "DEBUG": "1", "SECRET_KEY": "k" * 60})
    assert (mine["DEBUG"], mine["SECRET_KEY"]) == ("1", "k" * 60), "the environment wins"
    debug, redirect = settings_flags({k: env[k] for k in env if k != "PATH"})
    assert (debug, redirect) == (False, False)
    assert "--noreload" in server_command("127.0.0.1:9", reload=False)


def settings_flags(env: dict[str, str]) -> list:
    show = (
        "import json, django; django.setup(); from django.conf import settings as s; "
        "print(json.dumps([s.DEBUG, s.SECURE_SSL_REDIRECT]))"
    )
    answer = subprocess.run(
        [sys.executable, "-c", show], cwd=ROOT, env={**env, "PATH": "/usr/bin:/bin"},
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    return json.loads(answer.stdout.strip().splitlines()[-1])
