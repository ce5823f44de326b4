"""After a load run: wait until every uploaded recording's analysis has ended, then print
upload-to-result times (uploaded_at → finished_at of its run) from the database.

Exit status 0 only when every upload was analysed successfully, exactly once.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import django

os.environ.setdefault("DJANGO_SETTINGS_MODULE", "webapp.settings")
django.setup()

from webapp.recordings.models import AnalysisRun, Recording  # noqa: E402

UPLOADER_PREFIX = "load-uploader-"


def uploads():
    return Recording.objects.filter(uploaded_by__username__startswith=UPLOADER_PREFIX)


def unfinished() -> int:
    return AnalysisRun.objects.filter(
        recording__in=uploads(), status__in=("queued", "running")
    ).count()


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, max(0, round(q / 100 * len(ordered) + 0.5) - 1))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timeout", type=float, default=300.0)
    args = parser.parse_args()
    started = time.monotonic()
    while unfinished() and time.monotonic() - started < args.timeout:
        time.sleep(1.0)
    drained = time.monotonic() - started
    runs = list(AnalysisRun.objects.filter(recording__in=uploads()).select_related("recording"))
    per_recording: dict = {}
    for run in runs:
        per_recording.setdefault(run.recording_id, []).append(run)
    succeeded = [rs[0] for rs in per_recording.values() if [r.status for r in rs] == ["succeeded"]]
    seconds = [(r.finished_at - r.recording.uploaded_at).total_seconds() for r in succeeded]
    statuses: dict[str, int] = {}
    for run in runs:
        statuses[run.status] = statuses.get(run.status, 0) + 1
    print(f"\nuploads: {len(per_recording)} recordings, runs by status {statuses}; "
          f"queue drained {drained:.0f} s after the load stopped")  # fmt: skip
    if seconds:
        print(f"upload-to-result (database): p50 {statistics.median(seconds):.1f} s, "
              f"p95 {percentile(seconds, 95):.1f} s, p99 {percentile(seconds, 99):.1f} s, "
              f"max {max(seconds):.1f} s")  # fmt: skip
    for run in runs:
        if run.status == "failed":
            print(f"failed run {run.pk}: {run.user_error} {run.developer_error[:300]}")
    all_ok = bool(per_recording) and len(succeeded) == len(per_recording)
    raise SystemExit(0 if all_ok else 1)


if __name__ == "__main__":
    main()
