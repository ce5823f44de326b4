"""Fault injectors for the worker tests: a Redis server of the test's own that can be killed and
restarted empty, and a TCP proxy between the worker and PostgreSQL that can be cut."""

from __future__ import annotations

import contextlib
import selectors
import signal
import socket
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path


def free_port(preferred: int = 6390) -> int:
    """`preferred` if nothing listens there, else any free port (never the machine's 6379)."""
    for port in (preferred, 0):
        with socket.socket() as probe:
            try:
                probe.bind(("127.0.0.1", port))
            except OSError:
                continue
            return probe.getsockname()[1]
    raise RuntimeError("no free port")


class RedisServer:
    """A redis-server that keeps nothing on disk: killing it loses every queued message."""

    def __init__(self, directory: Path, port: int) -> None:
        self.directory = directory
        self.port = port
        self.process: subprocess.Popen[bytes] | None = None

    @property
    def url(self) -> str:
        return f"redis://127.0.0.1:{self.port}/0"

    def start(self) -> None:
        self.directory.mkdir(parents=True, exist_ok=True)
        command = [
            "redis-server",
            "--port", str(self.port),
            "--bind", "127.0.0.1",
            "--save", "",
            "--appendonly", "no",
            "--dir", str(self.directory),
        ]  # fmt: skip
        log = (self.directory / "redis.log").open("ab")
        self.process = subprocess.Popen(command, stdout=log, stderr=log)
        self.wait_until_answering()

    def wait_until_answering(self, timeout: float = 10.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.ping():
                return
            time.sleep(0.05)
        raise AssertionError("redis-server did not start")

    def ping(self) -> bool:
        try:
            with socket.create_connection(("127.0.0.1", self.port), timeout=1) as conn:
                conn.sendall(b"PING\r\n")
                return conn.recv(16).startswith(b"+PONG")
        except OSError:
            return False

    def queue_length(self, queue: str) -> int:
        with socket.create_connection(("127.0.0.1", self.port), timeout=2) as conn:
            conn.sendall(f"LLEN {queue}\r\n".encode())
            return int(conn.recv(64).strip().lstrip(b":"))

    def kill(self) -> None:
        """SIGKILL: the server dies without saving anything (it has nothing to save anyway)."""
        if self.process is not None and self.process.poll() is None:
            self.process.send_signal(signal.SIGKILL)
            self.process.wait(timeout=10)


class TcpProxy:
    """Forwards 127.0.0.1:port to a target; `cut()` drops every connection and refuses new
    ones until `restore()`, as a database server that goes away for a while would."""

    def __init__(self, target: tuple[str, int]) -> None:
        self.target = target
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.selector = selectors.DefaultSelector()
        self.peers: dict[socket.socket, socket.socket] = {}
        self.lock = threading.Lock()
        self.open = True
        self.running = True
        self.cuts = 0
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.selector.register(self.listener, selectors.EVENT_READ)
        self.thread.start()

    def serve(self) -> None:
        while self.running:
            for key, _ in self.selector.select(timeout=0.1):
                with self.lock:
                    if key.fileobj is self.listener:
                        self.accept()
                    else:
                        self.forward(key.fileobj)  # type: ignore[arg-type]

    def accept(self) -> None:
        client, _ = self.listener.accept()
        if not self.open:
            client.close()  # the "server" is down: connection refused, in effect
            return
        try:
            upstream = socket.create_connection(self.target, timeout=5)
        except OSError:
            client.close()
            return
        for one, other in ((client, upstream), (upstream, client)):
            self.peers[one] = other
            self.selector.register(one, selectors.EVENT_READ)

    def forward(self, source: socket.socket) -> None:
        other = self.peers.get(source)
        if other is None:
            return
        try:
            data = source.recv(65536)
            if data:
                other.sendall(data)
                return
        except OSError:
            pass
        self.drop(source)

    def drop(self, one: socket.socket) -> None:
        other = self.peers.pop(one, None)
        for sock in (one, other):
            if sock is None:
                continue
            self.peers.pop(sock, None)
            with contextlib.suppress(KeyError, ValueError):
                self.selector.unregister(sock)
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            sock.close()

    def cut(self) -> None:
        with self.lock:
            self.open = False
            self.cuts += 1
            for sock in list(self.peers):
                self.drop(sock)

    def restore(self) -> None:
        with self.lock:
            self.open = True

    def close(self) -> None:
        self.cut()
        self.running = False
        self.thread.join(timeout=5)
        self.listener.close()


@contextlib.contextmanager
def broker(url: str) -> Iterator[None]:
    """Point this process's Celery app (the web side that enqueues) at another broker."""
    from workers import app

    def reset_pools() -> None:
        app._pool = None
        with contextlib.suppress(AttributeError, KeyError):
            app.__dict__["amqp"]._producer_pool = None

    saved = app.conf.broker_url
    app.conf.broker_url = url
    reset_pools()
    try:
        yield
    finally:
        app.conf.broker_url = saved
        reset_pools()
