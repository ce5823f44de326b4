"""The Celery application, configured from the Django settings (``CELERY_*`` names).

Queues: analyses (and the short housekeeping tasks) go to the default queue (``CELERY_QUEUE``,
"analyses"), exercise-model builds to ``CELERY_MODELS_QUEUE`` ("models") and PDF reports to
``CELERY_REPORTS_QUEUE`` ("reports"). With prefetch 1 and late acknowledgement a worker holds one
message at a time, so a model build or a report never sits in front of an analysis, and dedicated
workers (``-Q analyses``) keep analysing while builds run elsewhere. A worker started without
``-Q`` (``make worker``) consumes every queue.

Every worker, wherever it runs, sets its own limits (workers/limits.py): a memory ceiling on each
pool process (``ANALYSIS_MEMORY_LIMIT_MB``) and Celery's soft and hard time limits; its pool and
beat processes die with it. What happens to a run whose pool process did not come back is
workers/task_guard.py's.
"""

from __future__ import annotations

import os
from typing import Any

from celery import Celery
from celery.signals import beat_embedded_init, task_prerun, worker_process_init, worker_ready
from kombu import Exchange, Queue

os.environ.setdefault("DJANGO_SETTINGS_MODULE", "webapp.settings")

app = Celery("physio")
app.config_from_object("django.conf:settings", namespace="CELERY")
app.autodiscover_tasks(["workers"], related_name="tasks")

# Task name → the setting naming its queue; tasks not listed use the default queue.
QUEUE_SETTING = {
    "workers.tasks.build_exercise_model": "CELERY_MODELS_QUEUE",
    "workers.tasks.rebuild_models_with_corrections": "CELERY_MODELS_QUEUE",
    "workers.tasks.refit_pass_thresholds": "CELERY_MODELS_QUEUE",
    "workers.tasks.make_report": "CELERY_REPORTS_QUEUE",
}


def queue_names() -> list[str]:
    """Every queue of the project, the default (analyses) queue first."""
    from django.conf import settings

    names = [app.conf.task_default_queue, settings.CELERY_MODELS_QUEUE]
    return list(dict.fromkeys([*names, settings.CELERY_REPORTS_QUEUE]))


def route_task(name: str, args: Any, kwargs: Any, options: Any, task: Any = None, **kw: Any):
    """Celery router: the queue of a task by its name (None: the default queue)."""
    from django.conf import settings

    setting = QUEUE_SETTING.get(name)
    return {"queue": getattr(settings, setting)} if setting else None


app.conf.task_routes = (route_task,)


@app.on_after_configure.connect
def _declare_queues(sender: Celery, **kwargs: Any) -> None:
    # A worker started without -Q consumes all of these.
    sender.conf.task_queues = [
        Queue(name, Exchange(name, type="direct"), routing_key=name) for name in queue_names()
    ]


@worker_ready.connect
def _resume_interrupted_analyses(**kwargs: Any) -> None:
    # Under `make run` nothing else would deliver an analysis cut short again (workers/tasks.py).
    from workers.tasks import resume_interrupted_local_runs

    resume_interrupted_local_runs()


@worker_process_init.connect
def _limit_pool_process(**kwargs: Any) -> None:
    # Each prefork pool process: the memory ceiling for the analyses it runs, and it dies with
    # the worker's main process (workers/limits.py).
    from workers.limits import die_with_parent

    die_with_parent()
    _limit_memory()


@beat_embedded_init.connect
def _beat_dies_with_the_worker(**kwargs: Any) -> None:
    # `celery worker -B` (make run): the beat process ends with the worker that started it.
    from workers.limits import die_with_parent

    die_with_parent()


@task_prerun.connect
def _limit_solo_worker(task: Any = None, **kwargs: Any) -> None:
    # Pools without pool processes (solo, threads) run tasks in the worker itself: the ceiling
    # goes on it before its first task. Eager tasks (tests, manage.py) run unlimited.
    if task is not None and not task.request.is_eager:
        _limit_memory()


def _limit_memory() -> None:
    from django.conf import settings

    from workers.limits import apply_memory_limit

    apply_memory_limit(int(settings.ANALYSIS_MEMORY_LIMIT_MB))  # the same again: no change
