"""`make run`: the web server and a real Celery worker beside it, with nothing to install.

``python -m workers.local [--demo] [ADDRESS:PORT]`` starts two processes and stops both, with
everything they started, when it is stopped (Ctrl-C, SIGTERM, SIGHUP) or when the server ends: each
runs in a process group of its own, which gets SIGTERM, then SIGKILL after ``STOP_SECONDS``; each
dies with the launcher if the launcher itself is killed (the kernel's parent-death signal, Linux),
and so do the worker's pool and beat processes (workers/celery.py). A worker that ends on its own
(killed, out of memory) is started again, up to ``WORKER_RESTARTS`` times, so uploads keep being
analysed:

* ``celery -A workers worker -B``: consumes every queue and runs the beat schedule (requeue lost
  runs, refresh the attention list …);
* ``manage.py runserver ADDRESS:PORT`` (daphne: HTTP and the live sessions' WebSockets), with
  DEBUG off, so everyone gets the site's own 404 and 500 pages: the launcher generates a secret
  key once (``DATA_DIR/secret_key``) and serves static files through WhiteNoise; plain HTTP on
  this machine, so no HTTPS redirect or secure-only cookies. ``DEBUG=1`` (or any of these set in
  the environment) wins; with DEBUG on, runserver also reloads itself when the code changes.

With ``--demo`` (`make run`) the server is ``manage.py serve_demo``: in the server's own process,
with the same environment, the migrations are applied and the demo clinic is loaded before it
serves (one start-up of the site's code, not three), so the demo's analyses go to the worker's
queue: the page is up as soon as the server is, and the demo's recordings show as being analysed,
as any upload does, until the worker is done. The worker then starts once the server answers on
its port (the database is ready by then), and does not compete with the server's start-up.

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

import contextlib
import os
import secrets
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

from workers.limits import die_with_parent

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_ADDRESS = "127.0.0.1:8000"
STOP_SECONDS = 6.0  # a worker finishing its task gets this long before everything is killed
WORKER_RESTARTS = 5  # a worker that keeps dying is a fault to show, not to hide
STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP)
# `make run` serves plain HTTP on this machine with DEBUG off: no HTTPS redirect, no secure-only
# cookies, static files from their folders (webapp/settings.py reads each of these).
PLAIN_HTTP = {
    "DEBUG": "0",
    "SECURE_SSL_REDIRECT": "0",
    "SESSION_COOKIE_SECURE": "0",
    "CSRF_COOKIE_SECURE": "0",
    "SECURE_HSTS_SECONDS": "0",
    "SECURE_HSTS_INCLUDE_SUBDOMAINS": "0",
    "SECURE_HSTS_PRELOAD": "0",
    "WHITENOISE_USE_FINDERS": "1",
}


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
    # Static files come from their folders (WHITENOISE_USE_FINDERS): an empty collected-files
    # folder of this data folder's own, so WhiteNoise does not warn of a missing one at each start.
    static_root = Path(out.setdefault("STATIC_ROOT", str(data_dir(out) / "static")))
    static_root.mkdir(parents=True, exist_ok=True)
    for name, value in PLAIN_HTTP.items():
        out.setdefault(name, value)
    if not out.get("SECRET_KEY"):
        out["SECRET_KEY"] = secret_key(data_dir(out))
    return out


def debug_on(env: Mapping[str, str]) -> bool:
    return env.get("DEBUG", "").strip().lower() in {"1", "true", "yes", "on"}


def secret_key(folder: Path) -> str:
    """This installation's secret key: generated at the first `make run`, kept in ``folder``
    (readable by its owner only) so sessions survive a restart."""
    path = folder / "secret_key"
    folder.mkdir(parents=True, exist_ok=True)
    try:
        descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        return path.read_text().strip()
    with os.fdopen(descriptor, "w") as handle:
        handle.write(secrets.token_urlsafe(50))
    return path.read_text().strip()


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


def server_command(address: str, *, reload: bool = True, demo: bool = False) -> list[str]:
    """runserver; with ``demo``, `serve_demo` (migrations and the demo clinic first)."""
    # Without the reloader the server is one process, which dies with the launcher.
    options = [] if reload else ["--noreload"]
    command = "serve_demo" if demo else "runserver"
    return [sys.executable, str(ROOT / "manage.py"), command, *options, address]


def answers(address: str) -> bool:
    """Something accepts connections at runserver's ``address`` ("[host:]port")."""
    host, _, port = address.rpartition(":")
    host = host.strip("[]")
    # A server on every interface answers on loopback too.
    host = {"": "127.0.0.1", "0": "127.0.0.1", "0.0.0.0": "127.0.0.1", "::": "::1"}.get(host, host)
    try:
        with socket.create_connection((host, int(port)), timeout=1.0):
            return True
    except OSError:
        return False


def start(command: Sequence[str], env: Mapping[str, str]) -> subprocess.Popen[bytes]:
    # A process group of its own, so stopping it also stops what it started (runserver's
    # reloaded child, the worker's pool and beat processes); and it dies with this process.
    return subprocess.Popen(
        list(command), env=dict(env), cwd=ROOT, start_new_session=True,
        preexec_fn=die_with(os.getpid()),  # noqa: PLW1509 (the launcher has one thread)
    )  # fmt: skip


def die_with(parent: int) -> Callable[[], None]:
    """A child's set-up between fork and exec: the parent-death signal; exit at once if the
    parent already ended before it was set."""

    def setup() -> None:
        die_with_parent(signal.SIGKILL)
        if os.getppid() != parent:
            os._exit(1)

    return setup


def signal_group(process: subprocess.Popen[bytes], signum: int) -> None:
    """Send ``signum`` to the process group ``process`` leads (its stragglers too, once it is
    gone itself)."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(process.pid, signum)


def stop_all(server: subprocess.Popen[bytes], worker: subprocess.Popen[bytes] | None) -> None:
    """SIGTERM to the server's group and to the worker if started (which stops its pool, ending
    its task first), up to ``STOP_SECONDS`` for both, then SIGKILL to both groups: nothing
    outlives this."""
    started = [process for process in (server, worker) if process is not None]
    signal_group(server, signal.SIGTERM)
    if worker is not None and worker.poll() is None:
        worker.terminate()
    deadline = time.monotonic() + STOP_SECONDS
    for process in started:
        with contextlib.suppress(subprocess.TimeoutExpired):
            process.wait(timeout=max(0.0, deadline - time.monotonic()))
    for process in started:
        signal_group(process, signal.SIGKILL)
        process.wait()


def ended_how(process: subprocess.Popen[bytes]) -> str:
    code = process.returncode
    return f"killed by signal {-code}" if code is not None and code < 0 else f"exit code {code}"


def say(message: str) -> None:
    print(f"workers.local: {message}", file=sys.stderr, flush=True)


def serve(address: str, env: Mapping[str, str], *, demo: bool = False) -> int:
    """Run the worker and the server until the server ends or this process is told to stop;
    with ``demo``, the server migrates and loads the demo clinic first (its analyses queued for
    the worker), and the worker starts once the server answers."""
    env = local_env(env)
    server = server_command(address, reload=debug_on(env), demo=demo)
    return supervise(worker_command(env), server, env, worker_after=address if demo else None)


def supervise(
    worker_argv: Sequence[str],
    server_argv: Sequence[str],
    env: Mapping[str, str],
    *,
    worker_after: str | None = None,
) -> int:
    """Keep a worker beside the server (restarted when it ends); returns the exit code. With
    ``worker_after`` (the server's address) the worker starts once the server answers there."""
    return Supervisor(worker_argv, server_argv, env, worker_after).run()


class Supervisor:
    """The server and the worker now running (a restarted one, after a death)."""

    def __init__(
        self,
        worker_argv: Sequence[str],
        server_argv: Sequence[str],
        env: Mapping[str, str],
        worker_after: str | None = None,
    ) -> None:
        self.worker_argv, self.server_argv, self.env = worker_argv, server_argv, env
        self.worker_after = worker_after
        self.stopping: list[int] = []

    def on_signal(self, signum: int, frame: object) -> None:
        self.stopping.append(signum)

    def run(self) -> int:
        previous = {signum: signal.signal(signum, self.on_signal) for signum in STOP_SIGNALS}
        self.server = start(self.server_argv, self.env)
        self.worker: subprocess.Popen[bytes] | None = None
        try:
            if self.worker_after is not None and not self.server_answers(self.worker_after):
                return self.ended()
            self.worker = start(self.worker_argv, self.env)
            return self.watch(self.worker)
        finally:
            stop_all(self.server, self.worker)
            for signum, handler in previous.items():
                signal.signal(signum, handler)

    def server_answers(self, address: str) -> bool:
        """Wait until the server answers at ``address``; False if it ended or a stop signal
        came first."""
        while self.server.poll() is None and not self.stopping:
            if answers(address):
                return True
            time.sleep(0.2)
        return False

    def ended(self) -> int:
        """The exit code once a stop signal came or the server ended (said on the terminal)."""
        if self.stopping:
            say(f"stopping ({signal.Signals(self.stopping[0]).name})")
            return 0
        say(f"the server ended ({ended_how(self.server)}); stopping the worker")
        return self.server.returncode or 0

    def watch(self, worker: subprocess.Popen[bytes]) -> int:
        """Until the server ends or a stop signal comes: restart the worker when it ends."""
        for restarts in range(WORKER_RESTARTS + 1):
            while self.server.poll() is None and worker.poll() is None and not self.stopping:
                time.sleep(0.2)
            if self.stopping or self.server.poll() is not None:
                return self.ended()
            signal_group(worker, signal.SIGKILL)  # what the dead worker left behind
            if restarts < WORKER_RESTARTS:
                say(f"the worker ended ({ended_how(worker)}); starting it again")
                worker = self.worker = start(self.worker_argv, self.env)
        say(f"the worker ended ({ended_how(worker)}) {WORKER_RESTARTS} times; stopping")
        return worker.returncode or 1


def main(argv: Sequence[str]) -> int:
    demo = "--demo" in argv
    rest = [arg for arg in argv if arg != "--demo"]
    address = rest[0] if rest else DEFAULT_ADDRESS
    return serve(address, os.environ, demo=demo)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
