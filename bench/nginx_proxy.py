"""docker-compose's proxy run outside Docker: Debian's nginx with deploy/proxy.conf.template,
rendered as the nginx image renders it, in a throw-away folder, in front of processes on loopback
ports. Used by `bench.bench_live --proxy` and tests/e2e/test_proxy_routing.py."""

from __future__ import annotations

import os
import re
import socket
import subprocess
import time
import urllib.request
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TEMPLATE = ROOT / "deploy/proxy.conf.template"
NGINX = Path("/usr/sbin/nginx")  # tests/e2e/ensure_programs.sh installs it


@dataclass
class RunningProxy:
    process: subprocess.Popen
    url: str
    access_log: Path
    error_log: Path

    def stop(self) -> None:
        self.process.terminate()
        try:
            self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


def render(template: str, values: dict[str, str]) -> str:
    """What the nginx image's envsubst does with the stack's settings: ${NAME} replaced (a name
    the template uses and the stack does not give is a KeyError), nginx's $variables kept."""
    return re.sub(r"\$\{(\w+)\}", lambda m: values[m.group(1)], template)


def main_config(folder: Path, site: Path) -> str:
    """The image's nginx.conf, reduced to what an nginx in a throw-away folder needs."""
    user = "user root root;\n" if os.geteuid() == 0 else ""  # its workers may write the folder
    temp = "".join(
        f"    {kind}_temp_path {folder / kind};\n"
        for kind in ("client_body", "proxy", "fastcgi", "uwsgi", "scgi")
    )
    return (
        f"{user}worker_processes auto;\ndaemon off;\npid {folder / 'nginx.pid'};\n"
        f"error_log {folder / 'error.log'} warn;\nevents {{ worker_connections 4096; }}\n"
        f"http {{\n{temp}    include {site};\n}}\n"
    )


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def start_proxy(folder: Path, web: str, live: tuple[str, str]) -> RunningProxy:
    """nginx on a free loopback port: pages and the API to ``web``, the live sessions'
    WebSockets to the two ``live`` addresses (host:port), as docker-compose.yml wires it."""
    if not NGINX.exists():
        raise RuntimeError(f"{NGINX} is missing: run tests/e2e/ensure_programs.sh")
    folder.mkdir(parents=True, exist_ok=True)
    port = free_port()
    values = {
        "PROXY_PORT": f"127.0.0.1:{port}",
        "PROXY_ACCESS_LOG": str(folder / "access.log"),
        "WEB_UPSTREAM": web,
        "LIVE_UPSTREAM_1": live[0],
        "LIVE_UPSTREAM_2": live[1],
    }
    site = folder / "default.conf"
    site.write_text(render(TEMPLATE.read_text(), values))
    conf = folder / "nginx.conf"
    conf.write_text(main_config(folder, site))
    error_log = folder / "error.log"
    argv = [str(NGINX), "-p", str(folder), "-e", str(error_log), "-c", str(conf)]
    with (folder / "nginx.out").open("w") as out:
        process = subprocess.Popen(argv, stdout=out, stderr=subprocess.STDOUT)
    proxy = RunningProxy(process, f"http://127.0.0.1:{port}", folder / "access.log", error_log)
    _wait_until_it_answers(proxy)
    return proxy


def _wait_until_it_answers(proxy: RunningProxy) -> None:
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        try:
            urllib.request.urlopen(f"{proxy.url}/healthz", timeout=2)
            return
        except OSError:
            if proxy.process.poll() is not None:
                break
            time.sleep(0.2)
    proxy.stop()
    log = proxy.error_log.read_text() if proxy.error_log.exists() else ""
    raise RuntimeError("nginx did not answer:\n" + log)
