"""Uvicorn under cProfile, profiling from a signal on: where a live server's processor time goes
once it is warm (`bench.bench_live --server-profile FILE`).

    python -m bench.profiled_server OUT.prof [uvicorn's arguments]

SIGUSR1 starts the profile of processor time (`time.thread_time`; the bench sends it after its
warm-up session, so imports, model loading and compiled kernels are not in it); the statistics
are written to OUT.prof when the server stops. cProfile follows the thread that enabled it: the
event loop's, where the consumer, the aligner and the WebSocket protocol run (the database calls
Channels hands to worker threads are not in it).
"""

from __future__ import annotations

import cProfile
import runpy
import signal
import sys
import time
from types import FrameType


def main() -> None:
    out, rest = sys.argv[1], sys.argv[2:]
    profile = cProfile.Profile(time.thread_time)  # processor time: not the waits

    def start(_signum: int, _frame: FrameType | None) -> None:
        profile.enable()

    def stop(_signum: int, _frame: FrameType | None) -> None:
        raise SystemExit(0)

    signal.signal(signal.SIGUSR1, start)
    # Uvicorn shuts down on SIGTERM, then raises it again under the handler it found: this one,
    # so that the statistics are written instead of the process ending at once
    signal.signal(signal.SIGTERM, stop)
    sys.argv = ["uvicorn", *rest]
    try:
        runpy.run_module("uvicorn", run_name="__main__")
    finally:
        profile.disable()
        profile.dump_stats(out)


if __name__ == "__main__":
    main()
