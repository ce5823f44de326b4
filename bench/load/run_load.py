"""Load run, start to finish: a fresh PostgreSQL database, gunicorn, two Celery workers on Redis,
locust for a fixed time on loopback, then the figures; everything it started is stopped and the
database dropped at the end.

    python -m bench.load.run_load [--duration 60] [--port 8100] [--keep-db]

Its own database (`load`), Redis database number and Celery queue keep it apart from anything
else running on the machine. Prints p50/p95/p99 per page and API call (from locust), errors, and
upload-to-result times for every upload (from the database, after waiting for the queue to drain).
"""

from __future__ import annotations

import argparse
import csv
import os
import shutil
import signal
import subprocess
import sys
import time
import urllib.request
from contextlib import ExitStack
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
OUT = ROOT / "var" / "load"
TARGET_MS = 300.0
DRAIN_TIMEOUT_S = 300.0


def service_env(args) -> dict[str, str]:
    env = dict(os.environ)
    env.update(
        DATABASE_URL=f"postgres://postgres@127.0.0.1:5432/{args.db}",
        REDIS_URL=args.redis,
        CELERY_QUEUE=f"load-{os.getpid()}",
        DATA_DIR=str(OUT / "data"),
        DEBUG="0",
        # Plain HTTP on loopback, no TLS proxy in front: no redirect to https, cookies sent back.
        SECURE_SSL_REDIRECT="0",
        SESSION_COOKIE_SECURE="0",
        CSRF_COOKIE_SECURE="0",
        DEMO_ALLOWED="1",  # the demo clinic's real analysed recordings, in a throw-away database
        SECRET_KEY=env.get("SECRET_KEY", "load-run-not-a-secret-" + "y" * 40),
        LOG_LEVEL="WARNING",
        LOAD_PLAN=str(OUT / "plan.json"),
        LOAD_THERAPISTS=str(args.therapists),
        LOAD_UPLOADERS=str(args.uploaders),
    )
    return env


def run(command: list[str], env: dict[str, str]) -> None:
    print("$", " ".join(command), flush=True)
    subprocess.run(command, env=env, cwd=ROOT, check=True)


def fresh_database(args, env: dict[str, str]) -> None:
    pg = ["-h", "127.0.0.1", "-U", "postgres"]
    run(["dropdb", *pg, "--force", "--if-exists", args.db], env)
    run(["createdb", *pg, args.db], env)
    run([str(BIN / "python"), "manage.py", "migrate", "-v0"], env)
    eager = {k: v for k, v in env.items() if k != "REDIS_URL"}
    run([str(BIN / "python"), "-m", "bench.load.setup_load", "--plan", env["LOAD_PLAN"]], eager)


def start(stack: ExitStack, name: str, command: list[str], env: dict[str, str]) -> None:
    log = open(OUT / f"{name}.log", "w")  # noqa: SIM115 (closed by the stack)
    stack.callback(log.close)
    process = subprocess.Popen(
        command, env=env, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, start_new_session=True
    )
    stack.callback(stop, process)
    print(f"started {name} (pid {process.pid})", flush=True)


def stop(process: subprocess.Popen) -> None:
    """Stop one process we started, and its children (its own session), by its id."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGTERM)
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()


def start_services(stack: ExitStack, args, env: dict[str, str]) -> None:
    gunicorn = [str(BIN / "gunicorn"), "webapp.wsgi", "-b", f"127.0.0.1:{args.port}"]
    gunicorn += ["-k", "gthread", "--workers", str(args.web_workers), "--threads", "4"]
    # Keep idle connections open longer than a user's think time (as the reverse proxy would);
    # with gunicorn's 2 s default the server closes them as the client reuses them (resets).
    gunicorn += ["--keep-alive", "10"]
    start(stack, "gunicorn", gunicorn, env)
    for index in (1, 2):
        # Analyses are batch work: at a lower CPU priority they use what the web leaves idle
        # instead of making every page wait behind them (0 turns this off).
        celery = ["nice", "-n", str(args.worker_nice)] if args.worker_nice else []
        celery += [str(BIN / "celery"), "-A", "workers", "worker", "--concurrency", "1"]
        celery += ["-Q", env["CELERY_QUEUE"], "-n", f"load{index}@%h", "--loglevel", "WARNING"]
        start(stack, f"worker{index}", celery, env)
    wait_healthy(args.port)


def wait_healthy(port: int, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/healthz", timeout=2) as reply:
                if reply.status == 200:
                    return
        except OSError:
            pass
        time.sleep(0.5)
    raise SystemExit("gunicorn did not become healthy; see var/load/gunicorn.log")


def run_locust(args, env: dict[str, str]) -> None:
    command = [str(BIN / "locust"), "-f", "bench/load/locustfile.py", "--headless"]
    users = args.therapists + args.uploaders
    command += ["-u", str(users), "-r", "10", "-t", f"{args.duration}s", "--stop-timeout", "0"]
    command += ["--host", f"http://127.0.0.1:{args.port}", "--csv", str(OUT / "locust")]
    command += ["--only-summary", "--loglevel", "WARNING"]
    subprocess.run(command, env=env, cwd=ROOT, check=False)


def print_locust_table() -> bool:
    """The per-endpoint table; True when every GET's p95 is under the target and nothing failed."""
    with open(OUT / "locust_stats.csv") as handle:
        rows = list(csv.DictReader(handle))
    print("\n| request | count | errors | p50 ms | p95 ms | p99 ms | max ms | p95 < 300 ms |")
    print("|---|---:|---:|---:|---:|---:|---:|---|")
    ok = True
    for row in rows:
        if row["Type"] == "" or row["Name"] == "Aggregated":
            continue
        p95 = float(row["95%"])
        is_read = row["Type"] == "GET"
        verdict = "yes" if p95 < TARGET_MS else f"**no** (+{p95 - TARGET_MS:.0f})"
        verdict = verdict if is_read else ""
        ok &= int(row["Failure Count"]) == 0 and (not is_read or p95 < TARGET_MS)
        print(
            f"| {row['Type']} {row['Name']} | {row['Request Count']} | {row['Failure Count']} | "
            f"{row['50%']} | {row['95%']} | {row['99%']} | {float(row['Max Response Time']):.0f} "
            f"| {verdict} |"
        )
    with open(OUT / "locust_failures.csv") as handle:
        for failure in csv.DictReader(handle):
            print(f"error: {failure['Method']} {failure['Name']}: {failure['Error']} "
                  f"×{failure['Occurrences']}")  # fmt: skip
    return ok


def uploads_report(env: dict[str, str]) -> bool:
    """Waits for every upload's analysis, then prints upload-to-result times from the database."""
    command = [str(BIN / "python"), "-m", "bench.load.uploads", "--timeout", str(DRAIN_TIMEOUT_S)]
    return subprocess.run(command, env=env, cwd=ROOT, check=False).returncode == 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=int, default=60)
    parser.add_argument("--port", type=int, default=8100)
    parser.add_argument("--db", default="load")
    parser.add_argument("--redis", default="redis://127.0.0.1:6379/7")
    parser.add_argument("--web-workers", type=int, default=3)
    parser.add_argument("--therapists", type=int, default=50)
    parser.add_argument("--uploaders", type=int, default=20)
    parser.add_argument("--keep-db", action="store_true")
    parser.add_argument("--worker-nice", type=int, default=10, help="CPU niceness of the workers")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    shutil.rmtree(OUT / "data", ignore_errors=True)  # media of the previous run's database
    env = service_env(args)
    try:
        fresh_database(args, env)
        with ExitStack() as stack:
            start_services(stack, args, env)
            run_locust(args, env)
            uploads_ok = uploads_report(env)
        reads_ok = print_locust_table()
    finally:
        if not args.keep_db:
            pg = ["-h", "127.0.0.1", "-U", "postgres"]
            run(["dropdb", *pg, "--force", "--if-exists", args.db], env)
    print("\ntargets met" if reads_ok and uploads_ok else "\ntargets MISSED (see above)")


if __name__ == "__main__":
    main()
