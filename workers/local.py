"""`make run`: the web server and a real Celery worker beside it, with nothing to install.

``python -m workers.local [ADDRESS:PORT]`` starts two processes and stops both when it is stopped
(Ctrl-C, SIGTERM) or when the server ends; a worker that ends on its own (killed, out of memory)
is started again, up to ``WORKER_RESTARTS`` times, so uploads keep being analysed:

* ``celery -A workers worker -B``: consumes every queue and runs the beat schedule (requeue lost
  runs, refresh the attention list …);
* ``manage.py runserver ADDRESS:PORT`` (daphne: HTTP and the live sessions' WebSockets).

Both get ``LOCAL_BROKER_DIR`` (``DATA_DIR/broker``): the settings then use kombu's filesystem
transport, one file per message in that folder, and no eager execution, so an upload returns as
soon as the file is stored and the worker reports the analysis's progress as it goes.

Why a separate worker process on a folder of files, not a worker thread inside the server with
an in-memory broker: runserver's autoreloader restarts the server process at every code change,
which would kill a thread's analysis and lose its in-memory queue; the worker process outlives
those restarts, and messages waiting in the folder survive a restart of either process. The
analysis (numpy, numba) also never competes with requests for the server's interpreter lock. With
``REDIS_URL`` set the settings ignore ``LOCAL_BROKER_DIR`` and both use Redis.

The filesystem transport removes a message when the worker takes it, so an analysis cut short
(`make run` stopped, the worker killed) would be delivered by nothing else: each worker, as it
starts, queues again the runs left under way (`workers.tasks.resume_interrupted_local_runs`; one
interrupted too often fails with a reason). SQLite is shared by the two processes in WAL mode
with a 30 s busy timeout (webapp/settings.py).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_ADDRESS = "127.0.0.1:8000"
STOP_SECONDS = 10.0  # a worker finishing its task gets this long before it is killed
WORKER_RESTARTS = 5  # a worker that keeps dying is a fault to show, not to hide


def data_dir(env: Mapping[str, str]) -> Path:
    """The settings' DATA_DIR (``var/`` unless the environment names another folder)."""
    return Path(env.get("DATA_DIR") or ROOT / "var")


def local_env(env: Mapping[str, str]) -> dict[str, str]:
    """The environment of both processes: the broker folder under DATA_DIR, created here."""
    out = dict(env)
    broker = Path(out.get("LOCAL_BROKER_DIR") or data_dir(out) / "broker")
    for sub in ("queue", "control"):
        (broker / sub).mkdir(parents=True, exist_ok=True)
    out["LOCAL_BROKER_DIR"] = str(broker)
    out.setdefault("DJANGO_SETTINGS_MODULE", "webapp.settings")
    return out


def worker_command(env: Mapping[str, str]) -> list[str]:
    schedule = data_dir(env) / "celerybeat-schedule"
    return [
        sys.executable, "-m", "celery", "-A", "workers", "worker", "-B",
        f"--schedule={schedule}", "--loglevel=INFO",
        f"--concurrency={env.get('WORKER_CONCURRENCY', '2')}",
        # Gossip, mingle and remote control need a broadcast exchange; one local worker has no
        # peers to talk to.
        "--without-gossip", "--without-mingle", "--without-heartbeat",
    ]  # fmt: skip


def server_command(address: str) -> list[str]:
    return [sys.executable, str(ROOT / "manage.py"), "runserver", address]


def start(command: Sequence[str], env: Mapping[str, str]) -> subprocess.Popen[bytes]:
    # A session of its own, so stopping it also stops what it started (runserver's reloaded
    # child, the worker's pool processes).
    return subprocess.Popen(list(command), env=dict(env), cwd=ROOT, start_new_session=True)


def stop(process: subprocess.Popen[bytes], *, group: bool) -> None:
    """SIGTERM (to the process's group when ``group``: runserver's reloaded child; the worker
    stops its own pool, ending its task first), then SIGKILL to the group if it lingers."""
    if process.poll() is not None:
        return
    try:
        if group:
            os.killpg(process.pid, signal.SIGTERM)
        else:
            process.terminate()
        process.wait(timeout=STOP_SECONDS)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()
    except ProcessLookupError:
        pass


def ended_how(process: subprocess.Popen[bytes]) -> str:
    code = process.returncode
    return f"killed by signal {-code}" if code is not None and code < 0 else f"exit code {code}"


def say(message: str) -> None:
    print(f"workers.local: {message}", file=sys.stderr, flush=True)


def serve(address: str, env: Mapping[str, str]) -> int:
    """Run the worker and the server until the server ends or this process is told to stop."""
    env = local_env(env)
    return supervise(worker_command(env), server_command(address), env)


def supervise(
    worker_argv: Sequence[str], server_argv: Sequence[str], env: Mapping[str, str]
) -> int:
    """Keep a worker beside the server (restarted when it ends); returns the exit code."""
    worker = start(worker_argv, env)
    server = start(server_argv, env)

    def on_signal(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    previous_handler = signal.signal(signal.SIGTERM, on_signal)
    code = 0
    restarts = 0
    try:
        while server.poll() is None:
            if worker.poll() is not None:
                if restarts == WORKER_RESTARTS:
                    say(f"the worker ended ({ended_how(worker)}) {restarts} times; stopping")
                    code = worker.returncode or 1
                    break
                restarts += 1
                say(f"the worker ended ({ended_how(worker)}); starting it again")
                worker = start(worker_argv, env)
            time.sleep(0.5)
        else:
            code = server.returncode or 0
            say(f"the server ended ({ended_how(server)}); stopping the worker")
    except KeyboardInterrupt:
        pass
    finally:
        stop(server, group=True)
        stop(worker, group=False)
        signal.signal(signal.SIGTERM, previous_handler)
    return code


def main(argv: Sequence[str]) -> int:
    address = argv[0] if argv else DEFAULT_ADDRESS
    return serve(address, os.environ)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
