"""Queues: model builds and reports go to queues of their own so they never delay analyses;
one message at a time per worker process, acknowledged when done; a worker without -Q consumes
every queue."""

from __future__ import annotations

import pytest

from workers import app
from workers.celery import queue_names

ROUTES = {
    "workers.tasks.analyse_recording": "analyses",
    "workers.tasks.inspect_recording": "analyses",
    "workers.tasks.reap_stuck_runs": "analyses",
    "workers.tasks.refresh_attention": "analyses",
    "workers.tasks.build_exercise_model": "models",
    "workers.tasks.rebuild_models_with_corrections": "models",
    "workers.tasks.make_report": "reports",
}


@pytest.mark.parametrize(("task", "queue"), ROUTES.items())
def test_each_task_goes_to_its_queue(task, queue):
    import workers.tasks  # noqa: F401  (registers the tasks)

    assert task in app.tasks
    route = app.amqp.router.route({}, task, (), {})
    assert route["queue"].name == queue


def test_workers_take_one_message_at_a_time_and_ack_when_done():
    assert app.conf.worker_prefetch_multiplier == 1
    assert app.conf.task_acks_late is True
    assert app.conf.task_reject_on_worker_lost is True


def test_a_worker_without_q_consumes_every_queue():
    assert queue_names() == ["analyses", "models", "reports"]
    assert {queue.name for queue in app.conf.task_queues} == {"analyses", "models", "reports"}
