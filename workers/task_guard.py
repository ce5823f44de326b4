"""What the worker's main process does when the pool process analysing a run did not come back.

The analysis itself ends every run it can with a reason (workers/analysis_task.py, including the
memory ceiling's MemoryError and the soft time limit). Two endings it cannot report, because its
process is gone; Celery tells the worker's main process, which calls these hooks:

* the hard time limit (``ANALYSIS_TIME_LIMIT``) killed it: the run fails with the time limit's
  reason (`AnalysisTask.on_failure`; Celery acknowledges the message, nothing runs it again);
* it died otherwise (killed by the kernel's out-of-memory killer, a crash, a signal): the run goes
  back to QUEUED at once, so the message Celery puts back in the queue can claim it (one more
  attempt), or fails with a reason when it had its last attempt (`AnalysisRequest.on_failure`).

A worker killed whole (main process included) leaves the run RUNNING; the broker's redelivery
(Redis) or the next worker's start (`make run`) takes it, through the same attempt count.
"""

from __future__ import annotations

import logging
from typing import Any

from billiard.exceptions import TimeLimitExceeded, WorkerLostError
from celery import Task
from celery.worker.request import Request

log = logging.getLogger(__name__)


def run_id_of(args: Any, kwargs: Any) -> str | None:
    """The run id of an ``analyse_recording`` call, however it was passed."""
    if kwargs and kwargs.get("run_id"):
        return str(kwargs["run_id"])
    return str(args[0]) if args else None


class AnalysisRequest(Request):
    """The main process's view of one analysis message."""

    def on_failure(self, exc_info: Any, send_failed_event: bool = True, return_ok: bool = False):
        error = getattr(exc_info.exception, "exc", exc_info.exception)
        run_id = run_id_of(self.args, self.kwargs)
        if isinstance(error, WorkerLostError) and run_id:
            from workers.housekeeping import release_lost_run

            try:  # before the message goes back to the queue
                outcome = release_lost_run(run_id)
                log.warning("analysis %s: its pool process died; run %s", run_id, outcome)
            except Exception:  # the reaper or the next claim still ends it
                log.exception("analysis %s: could not release the run", run_id)
        return super().on_failure(exc_info, send_failed_event, return_ok)


class AnalysisTask(Task):
    """The analysis task's class: its requests are `AnalysisRequest`s."""

    Request = AnalysisRequest

    def on_failure(self, exc: Any, task_id: str, args: Any, kwargs: Any, einfo: Any) -> None:
        run_id = run_id_of(args, kwargs)
        if isinstance(exc, TimeLimitExceeded) and run_id:
            from django.conf import settings

            from workers.housekeeping import fail_timed_out

            try:
                fail_timed_out(run_id, float(settings.ANALYSIS_TIME_LIMIT))
            except Exception:  # the reaper still ends it
                log.exception("analysis %s: could not fail the timed-out run", run_id)
