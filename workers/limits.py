"""What a worker process may take from the machine, set inside the worker itself.

The limits live in the process that runs the analyses, not in whatever started it, so they hold
alike under `make run`'s launcher (workers/local.py), docker-compose and `make worker` on another
machine (workers/celery.py applies them as each pool process starts):

* a memory ceiling (``ANALYSIS_MEMORY_LIMIT_MB``, 0: none) on each pool process. It is the
  kernel's data-segment limit (``RLIMIT_DATA``: the private memory a process writes, which is
  what numpy's arrays take), not its address-space limit (``RLIMIT_AS``), which also counts
  shared libraries and the address space reserved for threads and so grows with the machine's
  core count rather than with the analysis. An allocation past it raises MemoryError in the
  analysis, which then fails with `MEMORY_MESSAGE`; the process lives on.
* soft and hard time limits (``ANALYSIS_SOFT_TIME_LIMIT``, ``ANALYSIS_TIME_LIMIT``; Celery's
  own): the soft one raises in the analysis, which fails with `time_limit_message`; the hard one
  kills the pool process and the worker fails the run (workers/celery.py's `AnalysisTask`).
* the pool processes (and the beat process) of a worker started by the launcher die with their
  parent (`die_with_parent`), so nothing of `make run` outlives it even when it is killed.
"""

from __future__ import annotations

import ctypes
import logging
import resource
import signal
import sys

from billiard.exceptions import SoftTimeLimitExceeded
from django.conf import settings

# Raised inside an analysis that went past this server's limits (caught by workers.analysis_task).
LIMIT_ERRORS: tuple[type[BaseException], ...] = (MemoryError, SoftTimeLimitExceeded)
log = logging.getLogger(__name__)
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>

MEMORY_MESSAGE = (
    "This recording needs more memory than this server allows for one analysis, so its analysis "
    "was stopped; trying again will not help. A shorter recording, or one at a lower frame "
    "rate, can be analysed (or ask your administrator to raise the limit)."
)


def died_too_often_message(attempts: int) -> str:
    """The plain reason of a run whose worker ended under it ``attempts`` times."""
    times = {1: "once", 2: "twice"}.get(attempts, f"{attempts} times")
    return (
        f"The analysis stopped {times} before it could finish (the service running it ended "
        "while it worked, for example because the recording needed more memory or time than "
        "this server allows), so it was not tried again; trying again will not help. If the "
        "recording looks right to you, tell your administrator."
    )


def time_limit_message(seconds: float) -> str:
    """The plain reason of an analysis stopped by the time limit (``seconds`` long)."""
    span = f"{seconds:g} seconds" if seconds < 120 else f"{round(seconds / 60)} minutes"
    return (
        f"The analysis took longer than the {span} this server allows for one "
        "analysis, so it was stopped; trying again will not help. A shorter recording can be "
        "analysed (or ask your administrator to raise the limit)."
    )


def limit_reason(error: BaseException) -> str:
    """The plain reason of an analysis stopped by one of `LIMIT_ERRORS`."""
    if isinstance(error, SoftTimeLimitExceeded):
        return time_limit_message(getattr(settings, "ANALYSIS_SOFT_TIME_LIMIT", 0))
    return MEMORY_MESSAGE


def apply_memory_limit(megabytes: int) -> int | None:
    """Cap this process's data segment at ``megabytes`` (never above a lower existing hard
    limit); returns the ceiling in bytes, or None when ``megabytes`` is 0 (no ceiling)."""
    if megabytes <= 0:
        return None
    ceiling = megabytes * 1024 * 1024
    _, hard = resource.getrlimit(resource.RLIMIT_DATA)
    if hard != resource.RLIM_INFINITY:
        ceiling = min(ceiling, hard)
    resource.setrlimit(resource.RLIMIT_DATA, (ceiling, ceiling))
    return ceiling


def memory_limit_bytes() -> int | None:
    """This process's data-segment ceiling in bytes, or None when there is none."""
    soft, _ = resource.getrlimit(resource.RLIMIT_DATA)
    return None if soft == resource.RLIM_INFINITY else soft


def die_with_parent(signum: int = signal.SIGKILL) -> bool:
    """Ask the kernel to send ``signum`` to this process when its parent ends (Linux only).

    Used as ``preexec_fn`` by the launcher for its children and by a launched worker's pool
    processes. Returns False where the call does not exist."""
    if _LIBC is None:
        return False
    return _LIBC.prctl(PR_SET_PDEATHSIG, signum, 0, 0, 0) == 0


# Loaded once, in the parent: a `preexec_fn` runs between fork and exec, where loading a library
# is not safe.
_LIBC = ctypes.CDLL(None, use_errno=True) if sys.platform.startswith("linux") else None
