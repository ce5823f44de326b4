"""The docker-compose stack's front, run for real: nginx with deploy/proxy.conf.template (rendered
as the nginx image renders it) in front of gunicorn serving pages and the API, and two Uvicorn
processes serving the live sessions' WebSockets, as docker-compose.yml starts them.

A live session's aligner state lives in one process, so the proxy must send every connection of a
session to the same process and spread the sessions over both. Sixteen capture clients stream
through the proxy at 120 frames/s; each then connects again, as after a dropped connection, and
must find the server holding every frame it sent (round-robin routing would lose about half of
them). The proxy's log says which process served each connection.

Needs Debian's nginx (tests/e2e/ensure_programs.sh, run by .ci/run).
"""

from __future__ import annotations

import asyncio
import os
import re
import time
import urllib.request
from collections import defaultdict
from pathlib import Path

import pytest

from bench.bench_live import (
    recording_120,
    run_clients,
    server_env,
    setup_world,
    start_server,
    stop_server,
)
from bench.nginx_proxy import free_port, start_proxy

pytestmark = pytest.mark.e2e
SESSIONS = 16
FPS = 120.0


def redis_url() -> str | None:
    """The machine's Redis (as docker-compose's Redis channel layer), on a database of its own."""
    url = os.environ.get("REDIS_URL")
    return None if not url else re.sub(r"/\d*$", "", url) + "/13"


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    folder = Path(tmp_path_factory.mktemp("proxy-stack"))
    env = server_env(folder, redis_url())
    world = setup_world(env)
    ports = {"web": free_port(), "live-1": free_port(), "live-2": free_port()}
    procs = [start_server("gunicorn", env, ports["web"], folder / "web.log")]
    for name in ("live-1", "live-2"):
        procs.append(start_server("uvicorn", env, ports[name], folder / f"{name}.log"))
    address = {name: f"127.0.0.1:{port}" for name, port in ports.items()}
    live = (address["live-1"], address["live-2"])
    try:
        proxy = start_proxy(folder / "nginx", address["web"], live)
        try:
            yield proxy, world, address
        finally:
            proxy.stop()
    finally:
        for proc in procs:
            stop_server(proc)


def routes(access_log: Path) -> dict[str, set[str]]:
    """Request path -> the upstream addresses that served it, from the proxy's log."""
    served: dict[str, set[str]] = defaultdict(set)
    for line in access_log.read_text().splitlines():
        match = re.search(r'"\w+ (\S+) [^"]*" (\d+) .* upstream=(\S+)', line)
        if match:
            served[match.group(1)].add(match.group(3))
    return served


def logged(access_log: Path, marker: str, count: int = 1) -> None:
    """Wait (up to 10 s) until ``count`` lines of the proxy's log hold ``marker``: nginx writes a
    request's line when it has finished with it, which can be after the client has its answer."""
    deadline = time.monotonic() + 10
    while True:
        lines = [line for line in access_log.read_text().splitlines() if marker in line]
        if len(lines) >= count or time.monotonic() > deadline:
            return
        time.sleep(0.2)


def socket_routes(access_log: Path, connections: int) -> dict[str, set[str]]:
    """The WebSocket paths' upstreams, once the proxy has logged every connection (it logs one
    when it closes)."""
    logged(access_log, " /ws/", connections)
    return {path: ups for path, ups in routes(access_log).items() if path.startswith("/ws/")}


def test_pages_and_api_reach_gunicorn_through_the_proxy(stack):
    proxy, _, address = stack
    with urllib.request.urlopen(f"{proxy.url}/accounts/login/", timeout=10) as response:
        assert response.status == 200
        assert b'name="password"' in response.read()
    logged(proxy.access_log, " /accounts/login/ ")
    assert routes(proxy.access_log)["/accounts/login/"] == {address["web"]}


def test_each_live_session_stays_on_one_process_and_sessions_use_both(stack):
    proxy, world, address = stack
    rec = recording_120(seconds=1.5, fps=FPS, batch=3)
    clients = asyncio.run(run_clients([proxy.url], world, SESSIONS, rec, FPS, warmed=lambda: None))

    # every session answered through the proxy, nothing refused, every frame held on reconnecting
    assert all(client.latencies for client in clients)
    assert sum(client.errors for client in clients) == 0
    assert all(client.held for client in clients), "a reconnect reached a process without it"

    live = {address["live-1"], address["live-2"]}
    sockets = socket_routes(proxy.access_log, connections=2 * (SESSIONS + 1))
    assert len(sockets) == SESSIONS + 1  # the measured sessions and the warm-up one
    assert all(len(ups) == 1 and ups <= live for ups in sockets.values()), sockets
    # 17 sessions all on one process by chance: 1 in 65,536
    assert set().union(*sockets.values()) == live
    # the sessions were created through the proxy, by gunicorn
    logged(proxy.access_log, " /api/v1/live-sessions/ ")
    assert routes(proxy.access_log)["/api/v1/live-sessions/"] == {address["web"]}
