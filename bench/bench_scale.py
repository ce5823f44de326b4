"""Latency and query counts of the therapist's pages on a large clinic.

Run against a throw-away PostgreSQL database filled by `manage.py fill_large_clinic` (10,000
patients, 1,000,000 analysis runs); `make bench-scale` creates, fills, measures and drops it.

    DATABASE_URL=postgres://postgres@127.0.0.1:5432/big python -m bench.bench_scale \
        [--clinic "Large clinic"] [--requests 50] [--warmup 5]

In-process Django test client with DEBUG off, signed in as one of the clinic's therapists; every
endpoint is requested `--warmup` times, then `--requests` times (warm), each time for another
patient of a fixed random sample (plus the patient with the most runs, reported on its own line).
Prints p50/p95/p99/max in ms and the number of SQL queries per request.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import random
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

os.environ.setdefault("DJANGO_SETTINGS_MODULE", "webapp.settings")
os.environ.setdefault("DEBUG", "0")
os.environ.setdefault("SECRET_KEY", "bench-scale-not-a-secret-" + "x" * 40)

import django

django.setup()

from django.db import connection  # noqa: E402
from django.db.models import Count  # noqa: E402
from django.test import Client  # noqa: E402
from django.test.utils import CaptureQueriesContext  # noqa: E402

from webapp.accounts.models import Clinic, User  # noqa: E402
from webapp.dashboard.precompute import refresh_clinic  # noqa: E402
from webapp.patients.models import Patient  # noqa: E402
from webapp.patients.progress_store import store_missing  # noqa: E402
from webapp.recordings.models import AnalysisRun  # noqa: E402

TARGET_MS = 100.0


@dataclass(frozen=True)
class Endpoint:
    name: str
    url: Callable[[Patient], str]


ENDPOINTS = (
    Endpoint("therapist dashboard  /", lambda p: "/"),
    Endpoint("patient list  /patients/", lambda p: "/patients/"),
    Endpoint("patient list, page 200", lambda p: "/patients/?page=200"),
    Endpoint("patient list, search", lambda p: f"/patients/?q={p.display_name.split()[-1]}"),
    Endpoint("patient history  /patients/{id}/", lambda p: f"/patients/{p.pk}/"),
    Endpoint("progress page  /patients/{id}/progress/", lambda p: f"/patients/{p.pk}/progress/"),
    Endpoint(
        "progress JSON  /patients/{id}/progress.json", lambda p: f"/patients/{p.pk}/progress.json"
    ),
    Endpoint("API patients  /api/v1/patients/", lambda p: "/api/v1/patients/"),
    Endpoint(
        "API history  /api/v1/patients/{id}/recordings/",
        lambda p: f"/api/v1/patients/{p.pk}/recordings/",
    ),
    Endpoint(
        "API progress  /api/v1/patients/{id}/progress/",
        lambda p: f"/api/v1/patients/{p.pk}/progress/",
    ),
)


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    index = min(len(ordered) - 1, max(0, round(q / 100.0 * len(ordered) + 0.5) - 1))
    return ordered[index]


def timed_get(client: Client, url: str) -> tuple[float, int, int, int]:
    """(milliseconds, SQL queries, status, bytes) of one GET."""
    with CaptureQueriesContext(connection) as queries:
        started = time.perf_counter()
        response = client.get(url, secure=True)  # as behind the TLS proxy: no redirect
        body = b"".join(response) if response.streaming else response.content
        elapsed = (time.perf_counter() - started) * 1000.0
    return elapsed, len(queries), response.status_code, len(body)


def measure(client: Client, endpoint: Endpoint, patients: list[Patient], args) -> dict:
    warm = [timed_get(client, endpoint.url(p))[0] for p in patients[: args.warmup]]
    # An endpoint taking seconds gets only a few requests: the verdict is clear, the run short.
    requests = args.requests if max(warm) < args.slow_ms else args.warmup
    times, queries, sizes = [], [], []
    for index in range(requests):
        ms, n, status, size = timed_get(client, endpoint.url(patients[index % len(patients)]))
        if status != 200:
            raise SystemExit(f"{endpoint.name}: HTTP {status}")
        times.append(ms)
        queries.append(n)
        sizes.append(size)
    return {
        "endpoint": endpoint.name,
        "requests": requests,
        "p50": statistics.median(times),
        "p95": percentile(times, 95),
        "p99": percentile(times, 99),
        "max": max(times),
        "queries": max(queries),
        "kB": statistics.median(sizes) / 1024,
    }


def print_table(rows: list[dict]) -> None:
    print("| endpoint | n | p50 ms | p95 ms | p99 ms | max ms | queries | kB | p95 < 100 ms |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in rows:
        over = r["p95"] - TARGET_MS
        ok = "yes" if over < 0 else f"**no** (+{over:.0f} ms)"
        print(
            f"| {r['endpoint']} | {r['requests']} | {r['p50']:.1f} | {r['p95']:.1f} | "
            f"{r['p99']:.1f} | {r['max']:.1f} | {r['queries']} | {r['kB']:.1f} | {ok} |"
        )


def heaviest_patient(clinic: Clinic) -> tuple[Patient, int]:
    row = (
        AnalysisRun.objects.filter(recording__clinic=clinic)
        .values("recording__patient")
        .annotate(n=Count("id"))
        .order_by("-n")
        .first()
    )
    return Patient.objects.get(pk=row["recording__patient"]), row["n"]


def describe(clinic: Clinic) -> str:
    patients = Patient.objects.filter(clinic=clinic).count()
    runs = AnalysisRun.objects.filter(recording__clinic=clinic).count()
    with connection.cursor() as cursor:
        cursor.execute("SELECT pg_size_pretty(pg_database_size(current_database()))")
        size = cursor.fetchone()[0]
    return f"clinic {clinic.name!r}: {patients:,} patients, {runs:,} analysis runs, database {size}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clinic", default="Large clinic")
    parser.add_argument("--requests", type=int, default=50)
    parser.add_argument("--warmup", type=int, default=5)
    parser.add_argument("--sample", type=int, default=50, help="patients cycled through")
    parser.add_argument("--slow-ms", type=float, default=2000.0, help="fewer requests if slower")
    parser.add_argument("--json", help="also write the figures to this file")
    args = parser.parse_args()
    if connection.vendor != "postgresql":
        raise SystemExit("Point DATABASE_URL at the PostgreSQL database of the large clinic.")
    clinic = Clinic.objects.get(name=args.clinic)
    therapist = User.objects.filter(clinic=clinic, role="therapist").order_by("username").first()
    ids = list(Patient.objects.filter(clinic=clinic).values_list("pk", flat=True))
    sample = random.Random(0).sample(ids, min(args.sample, len(ids)))
    patients = list(Patient.objects.filter(pk__in=sample))
    heavy, heavy_runs = heaviest_patient(clinic)
    client = Client()
    client.force_login(therapist)
    print(f"{describe(clinic)}; {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, Python {platform.python_version()}")  # fmt: skip
    # The fill writes rows directly: build the stored attention list as the beat task would.
    started = time.perf_counter()
    flagged = refresh_clinic(clinic.pk)
    print(f"attention list refreshed (beat task): {flagged:,} patients flagged in "
          f"{time.perf_counter() - started:.1f} s")  # fmt: skip
    # The fill stores the progress points as workers do; a database filled before it did gets
    # them here (none missing: one query).
    started = time.perf_counter()
    stored = store_missing(AnalysisRun.objects.filter(recording__clinic=clinic))
    print(f"progress points missing before the bench: {stored:,} (stored in "
          f"{time.perf_counter() - started:.1f} s)")  # fmt: skip
    print(f"{args.requests} warm requests per endpoint over {len(patients)} patients\n")
    rows = [measure(client, endpoint, patients, args) for endpoint in ENDPOINTS]
    for endpoint in ENDPOINTS:
        if "{id}" in endpoint.name:
            row = measure(client, endpoint, [heavy], args)
            rows.append({**row, "endpoint": f"{endpoint.name} (heaviest: {heavy_runs} runs)"})
    print_table(rows)
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(rows, handle, indent=1)


if __name__ == "__main__":
    main()
